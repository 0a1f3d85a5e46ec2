#pragma once
// Exact homogeneous states of the paper's hyperelastic laws, written from the formulas and independent of the
// material plugins: what the verification tests compare whole runs with.
#include <cmath>
#include <functional>

#include "mtled/types.hpp"

namespace mtled::test {

using Energy = std::function<double(const Vec3&)>;  // strain energy density of the principal stretches

// The paper's eq. (1): W = sum_i 2 mu / alpha^2 (lambda_bar_i^alpha - 1) + (J - 1)^2 / D,
// lambda_bar_i = J^(-1/3) lambda_i. Written here from the formula, independently of the plugins.
inline Energy ogden(double mu, double alpha, double D) {
  return [=](const Vec3& l) {
    const double J = l.prod(), s = std::cbrt(1.0 / J);
    double w = 0.0;
    for (int i = 0; i < 3; ++i) w += std::pow(s * l[i], alpha) - 1.0;
    return 2.0 * mu / (alpha * alpha) * w + (J - 1.0) * (J - 1.0) / D;
  };
}
// Neo-Hookean: W = mu/2 (J^(-2/3) I1 - 3) + (J - 1)^2 / D.
inline Energy neo_hookean(double mu, double D) {
  return [=](const Vec3& l) {
    const double J = l.prod();
    return 0.5 * mu * (std::pow(J, -2.0 / 3.0) * l.squaredNorm() - 3.0) + (J - 1.0) * (J - 1.0) / D;
  };
}

// dW/dlambda_i by central differences: truncation ~ h^2 W''' ~ 1e-12 relative, round-off ~ 1e-10.
inline double nominal_stress(const Energy& W, Vec3 l, int i) {
  const double h = 1e-6;
  Vec3 a = l, b = l;
  a[i] += h;
  b[i] -= h;
  return (W(a) - W(b)) / (2.0 * h);
}

// Homogeneous uniaxial state at axial stretch `stretch` with free sides: the lateral stretch that makes the lateral
// nominal stress vanish (bisection to round-off).
inline double exact_uniaxial_lateral_stretch(const Energy& W, double stretch) {
  double lo = 0.8, hi = 1.5;
  for (int k = 0; k < 200; ++k) {
    const double mid = 0.5 * (lo + hi);
    (nominal_stress(W, Vec3(mid, mid, stretch), 0) > 0.0 ? hi : lo) = mid;
  }
  return lo;
}
// ... and its axial nominal stress P_33 (Pa).
inline double exact_uniaxial_stress(const Energy& W, double stretch) {
  const double lateral = exact_uniaxial_lateral_stretch(W, stretch);
  return nominal_stress(W, Vec3(lateral, lateral, stretch), 2);
}

}  // namespace mtled::test
