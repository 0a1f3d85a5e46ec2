#pragma once
// The damped central-difference update both integrators share (mass-proportional damping c, step h; the
// form of Joldes, Wittek and Miller, IJNMBE 2011, for dynamic relaxation):
//   u+ = u + beta (u - u-) + alpha M^-1 (f_ext - f_int).
// beta = 1, alpha = h^2 is the undamped central difference. One streaming pass of a few operations per unknown:
// serial, since waking threads for it costs more than it saves (and a waiting OpenMP thread spins on a core
// that another run sharing the machine may need).
#include <span>

namespace mtled {

inline void explicit_update(std::span<const double> u, std::span<const double> u_previous,
                            std::span<const double> f_ext, std::span<const double> f_int,
                            std::span<const double> nodal_mass, double alpha, double beta, std::span<double> u_next) {
  const std::size_t nodes = nodal_mass.size();
  for (std::size_t i = 0; i < nodes; ++i) {
    const double step = alpha / nodal_mass[i];
    for (std::size_t d = 3 * i; d < 3 * i + 3; ++d)
      u_next[d] = u[d] + beta * (u[d] - u_previous[d]) + step * (f_ext[d] - f_int[d]);
  }
}

}  // namespace mtled
