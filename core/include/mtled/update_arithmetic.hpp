#pragma once
// One unknown's damped central-difference update (explicit_update.hpp says the method), written once for the CPU
// engines and for a GPU backend's update kernel:
//   u+ = u + beta (u - u-) + (alpha / m) (f_ext - f - gamma (f - f-)).
#include <cstdint>

#include "mtled/host_device.hpp"

namespace mtled {

// Unknown d's u+, `step` = alpha / m of its node; f_ext null: no external forces. f_previous is read only where
// gamma != 0 (without it, the arithmetic of the update without stiffness damping, bit for bit).
MTLED_HOST_DEVICE inline double updated_unknown(std::int64_t d, const double* u, const double* u_previous,
                                                const double* f_ext, const double* f, const double* f_previous,
                                                double step, double beta, double gamma) {
  const double f_int = gamma != 0.0 ? f[d] + gamma * (f[d] - f_previous[d]) : f[d];
  return u[d] + beta * (u[d] - u_previous[d]) + step * ((f_ext != nullptr ? f_ext[d] : 0.0) - f_int);
}

}  // namespace mtled
