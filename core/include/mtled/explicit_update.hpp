#pragma once
// The damped central-difference update (mass-proportional damping c, step h; the form of Joldes, Wittek and
// Miller, IJNMBE 2011, for dynamic relaxation), with stiffness-proportional damping from the last two force
// evaluations (UpdateCoefficients):
//   u+ = u + beta (u - u-) + alpha M^-1 (f_ext - f_int - gamma (f_int - f_int-)).
// beta = 1, alpha = h^2, gamma = 0 is the undamped central difference. The CPU's loop of it (one unknown's arithmetic
// is update_arithmetic.hpp's, which a GPU backend shares), of dynamic relaxation's increment sums and of a step's sums
// (StepSums), for DiscreteSystem's defaults, the CPU engine and the mpi backend (which does the per-node work on a
// rank's own nodes).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <span>

#include "mtled/interfaces/integrator.hpp"
#include "mtled/update_arithmetic.hpp"

namespace mtled {

// u_next of nodes begin .. end - 1 (3 unknowns each); f_ext null: no external forces. f_int_previous is read only
// where gamma != 0.
inline void explicit_update(const double* u, const double* u_previous, const double* f_ext, const double* f_int,
                            const double* f_int_previous, const double* nodal_mass, const UpdateCoefficients& update,
                            double* u_next, std::size_t begin, std::size_t end) {
  for (std::size_t i = begin; i < end; ++i) {
    const double step = update.alpha / nodal_mass[i];
    for (std::size_t d = 3 * i; d < 3 * i + 3; ++d)
      u_next[d] = updated_unknown(static_cast<std::int64_t>(d), u, u_previous, f_ext, f_int, f_int_previous, step,
                                  update.beta, update.gamma);
  }
}

// Unknown d's part of increment_sums.
inline void add_increment_sums(std::size_t d, std::span<const double> u, std::span<const double> u_previous,
                               std::span<const double> f, std::span<const double> f_previous,
                               std::span<const double> nodal_mass, IncrementSums& sums) {
  const double du = u[d] - u_previous[d];
  sums.stiffness += du * (f[d] - f_previous[d]);
  sums.inertia += du * du * nodal_mass[d / 3];
}

// du.(f - f_previous) and du.M du for du = u - u_previous (3 unknowns per node), in unknown order on one thread:
// the order of the sums is part of the answer (dynamic relaxation tunes its damping to their ratio).
inline IncrementSums increment_sums(std::span<const double> u, std::span<const double> u_previous,
                                    std::span<const double> f, std::span<const double> f_previous,
                                    std::span<const double> nodal_mass) {
  IncrementSums sums;
  for (std::size_t i = 0; i < u.size(); ++i) add_increment_sums(i, u, u_previous, f, f_previous, nodal_mass, sums);
  return sums;
}

// Node i's part of a completed step's sums (StepSums): u_n = u, u_(n-1) = u_previous, u_(n+1) = u_next, u~ = free (the
// prediction before the projection), beta the update's factor on u_n - u_(n-1). `fastest_energy` is the largest
// |m_I (u_n - u_(n-1)).(u_(n+1) - u_n)| so far.
inline void add_step_sums(std::size_t i, const double* u, const double* u_previous, const double* u_next,
                          const double* free, const double* nodal_mass, double beta, StepSums& sums,
                          double& fastest_energy) {
  double added = 0.0, product = 0.0;
  for (std::size_t d = 3 * i; d < 3 * i + 3; ++d) {
    const double after = u_next[d] - u[d], before = free[d] - u[d], last = u[d] - u_previous[d];
    added += std::max(0.0, after * after - before * before);
    product += last * after;
    sums.largest_increment = std::max(sums.largest_increment, std::abs(after));
    sums.largest_residual_step = std::max(sums.largest_residual_step, std::abs(after - beta * last));
    sums.largest_displacement = std::max(sums.largest_displacement, std::abs(u_next[d]));
  }
  sums.projection_energy += nodal_mass[i] * added;
  const double e = nodal_mass[i] * product;
  sums.kinetic_product += e;
  if (std::abs(e) > fastest_energy) {
    fastest_energy = std::abs(e);
    sums.fastest_node = static_cast<Index>(i);
  }
}

// Adds a share's step sums (with its fastest_energy) to the total of the shares before it: shares in node order, so
// that the fastest node among equals is the first share's.
inline void combine_step_sums(const StepSums& share, double share_fastest_energy, StepSums& total,
                              double& fastest_energy) {
  total.largest_increment = std::max(total.largest_increment, share.largest_increment);
  total.largest_displacement = std::max(total.largest_displacement, share.largest_displacement);
  total.largest_residual_step = std::max(total.largest_residual_step, share.largest_residual_step);
  total.projection_energy += share.projection_energy;
  total.kinetic_product += share.kinetic_product;
  if (share_fastest_energy > fastest_energy) {
    fastest_energy = share_fastest_energy;
    total.fastest_node = share.fastest_node;
  }
}

}  // namespace mtled
