#pragma once
// The damped central-difference update (mass-proportional damping c, step h; the form of Joldes, Wittek and
// Miller, IJNMBE 2011, for dynamic relaxation):
//   u+ = u + beta (u - u-) + alpha M^-1 (f_ext - f_int).
// beta = 1, alpha = h^2 is the undamped central difference. The CPU's form, for DiscreteSystem::advance's default
// and the CPU engine; a device backend writes the same arithmetic in its own language.
#include <cstddef>

namespace mtled {

// u_next of nodes begin .. end - 1 (3 unknowns each); f_ext null: no external forces.
inline void explicit_update(const double* u, const double* u_previous, const double* f_ext, const double* f_int,
                            const double* nodal_mass, double alpha, double beta, double* u_next, std::size_t begin,
                            std::size_t end) {
  for (std::size_t i = begin; i < end; ++i) {
    const double step = alpha / nodal_mass[i];
    for (std::size_t d = 3 * i; d < 3 * i + 3; ++d)
      u_next[d] = u[d] + beta * (u[d] - u_previous[d]) + step * ((f_ext != nullptr ? f_ext[d] : 0.0) - f_int[d]);
  }
}

}  // namespace mtled
