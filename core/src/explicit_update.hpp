#pragma once
// The damped central-difference update (mass-proportional damping c, step h; the form of Joldes, Wittek and
// Miller, IJNMBE 2011, for dynamic relaxation):
//   u+ = u + beta (u - u-) + alpha M^-1 (f_ext - f_int).
// beta = 1, alpha = h^2 is the undamped central difference. The CPU's form of it and of dynamic relaxation's increment
// sums, for DiscreteSystem's defaults and the CPU engine; a device backend writes the same arithmetic in its own
// language.
#include <cstddef>
#include <span>

#include "mtled/interfaces/integrator.hpp"

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

// du.(f - f_previous) and du.M du for du = u - u_previous (3 unknowns per node), in unknown order on one thread:
// the order of the sums is part of the answer (dynamic relaxation tunes its damping to their ratio).
inline IncrementSums increment_sums(std::span<const double> u, std::span<const double> u_previous,
                                    std::span<const double> f, std::span<const double> f_previous,
                                    std::span<const double> nodal_mass) {
  IncrementSums sums;
  for (std::size_t i = 0; i < u.size(); ++i) {
    const double du = u[i] - u_previous[i];
    sums.stiffness += du * (f[i] - f_previous[i]);
    sums.inertia += du * du * nodal_mass[i / 3];
  }
  return sums;
}

}  // namespace mtled
