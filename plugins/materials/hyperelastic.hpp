#pragma once
// What the hyperelastic laws of the paper's eq. (1) share: the admissibility test of F, the volumetric
// term (1/D)(J - 1)^2, and the declarations of the parameters every one of them has (mu, D, density), so
// that their docs, units and ranges are written once.
#include <cmath>

#include "mtled/parameters.hpp"
#include "mtled/types.hpp"

namespace mtled::hyperelastic {

// Whether a law may be evaluated at F, with J = det F. The Material interface requires refusing an
// inverted or collapsed F (J <= 0) and non-finite entries instead of hiding them with |J| (which would let
// inverted material pass as a valid state); this is checked before any power of J is taken.
inline bool admissible(const Mat3& F, double& J) noexcept {
  J = F.determinant();
  return J > 0.0 && std::isfinite(J) && F.allFinite();
}

// J^(-2/3), the factor that makes the isochoric stretches J^(-1/3) lambda_i. Squaring the cube root (not
// taking the cube root of J^2) keeps it finite and nonzero for every finite J > 0.
inline double J_minus_two_thirds(double J) noexcept {
  const double cube_root = std::cbrt(J);
  return 1.0 / (cube_root * cube_root);
}

// U(J) = (1/D)(J - 1)^2, the volumetric part of eq. (1). Its share of S is J U'(J) C^-1, and its
// small-strain bulk modulus is U''(1) = 2/D.
class VolumetricPenalty {
 public:
  explicit VolumetricPenalty(double D) : inverse_D_(1.0 / D) {}
  double energy(double J) const noexcept { return (J - 1.0) * (J - 1.0) * inverse_D_; }
  double J_dU_dJ(double J) const noexcept { return 2.0 * inverse_D_ * J * (J - 1.0); }
  double bulk_modulus() const noexcept { return 2.0 * inverse_D_; }

 private:
  double inverse_D_;
};

// lambda + 2 mu = K + 4 mu / 3 of a law whose small-strain shear modulus is mu.
inline double p_wave_modulus(double shear_modulus, const VolumetricPenalty& volumetric) {
  return volumetric.bulk_modulus() + 4.0 * shear_modulus / 3.0;
}

// The parameters every law here declares: "mu" (Pa), "D" (1/Pa) and "density" (kg/m^3).
void declare_shear_modulus(ComponentDeclaration& declaration);
void declare_compressibility(ComponentDeclaration& declaration);
void declare_density(ComponentDeclaration& declaration);

}  // namespace mtled::hyperelastic
