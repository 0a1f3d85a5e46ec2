// One-term compressible Ogden law, the paper's eq. (1):
//   W = (2 mu / alpha^2)(J^(-alpha/3) sum_i lambda_i^alpha - 3) + (1/D)(J - 1)^2.
// Stress in principal form (as for any isotropic law of the principal stretches, e.g. Holzapfel, Nonlinear
// Solid Mechanics, 2000, sec. 6.5). For an isotropic W(lambda_1, lambda_2, lambda_3),
// S_i = (1/lambda_i) dW/dlambda_i along the eigenvectors of C. With dJ/dlambda_i = J / lambda_i,
//   dW/dlambda_i = (2 mu / alpha) J^(-alpha/3) (lambda_i^(alpha-1) - sum_j lambda_j^alpha / (3 lambda_i))
//                  + (2/D)(J - 1) J / lambda_i,
// so with b = (2 mu / alpha) J^(-alpha/3) and a = (2/D) J (J - 1) - (b/3) sum_j lambda_j^alpha,
//   S_i = a / lambda_i^2 + b lambda_i^(alpha - 2),   S = Q diag(S_i) Q^T,   C = Q diag(lambda_i^2) Q^T.
// Equal stretches cause no 0/0 here; what needs care is the eigen decomposition itself (symmetric_eigen3).
// alpha = 2 gives b = mu J^(-2/3) and S = b I + a C^-1: the neo-Hookean law. The small-strain shear
// modulus is (2 mu / alpha^2) alpha^2 / 2 = mu.
#include <cmath>
#include <limits>

#include "hyperelastic.hpp"
#include "mtled/interfaces/material.hpp"
#include "mtled/plugin.hpp"
#include "stress_batch.hpp"
#include "symmetric_eigen3.hpp"

namespace mtled {

class OgdenMaterial final : public Material {
 public:
  static void declare(ComponentDeclaration& d) {
    d.summary("one-term compressible Ogden hyperelastic solid, W = (2 mu / alpha^2)(J^(-alpha/3) sum_i "
              "lambda_i^alpha - 3) + (1/D)(J - 1)^2 (the paper's eq. (1)); alpha = 2 is neo-Hookean");
    hyperelastic::declare_shear_modulus(d);
    d.number("alpha")
        .unit("1")
        .nonzero()
        .doc("Ogden exponent on the principal stretches; it sets how the material stiffens: 2 is "
             "neo-Hookean, negative values stiffen more in compression; Sylgard 527 gel and brain tissue "
             "fits: about -1.3 to -4.7");
    hyperelastic::declare_compressibility(d);
    hyperelastic::declare_density(d);
    // Sylgard 527 gel, the paper's section 2.2.2 and Table 1 (Material 2): nu = 0.49.
    d.example({{"mu", 722.0}, {"alpha", -1.3}, {"D", 5.57738e-5}, {"density", 1000.0}});
  }

  explicit OgdenMaterial(const Parameters& p)
      : mu_(p.number("mu")),
        alpha_(p.number("alpha")),
        D_(p.number("D")),
        volumetric_(D_),
        density_(p.number("density")),
        half_alpha_(0.5 * alpha_),
        energy_factor_(2.0 * mu_ / (alpha_ * alpha_)),
        stress_factor_(2.0 * mu_ / alpha_) {}

  double density() const override { return density_; }
  double p_wave_modulus() const override { return hyperelastic::p_wave_modulus(mu_, volumetric_); }

  bool stress(const Mat3& F, Mat3& S) const noexcept override {
    double J;
    if (!hyperelastic::admissible(F, J)) return false;
    const SymmetricEigen3 principal = symmetric_eigen3(F.transpose() * F);
    const Vec3& stretch_squared = principal.values;
    // J^(-alpha/3) lambda_i^alpha, so that b lambda_i^alpha = (2 mu / alpha) isochoric[i]
    const Vec3 isochoric = isochoric_powers(stretch_squared, J);
    // sum / 3 is 1 exactly at F = I, so a = -2 mu / alpha there and S(I) = 0 exactly.
    const double a = volumetric_.J_dU_dJ(J) - stress_factor_ * (isochoric.sum() / 3.0);
    const Vec3 principal_stress = (Vec3::Constant(a) + stress_factor_ * isochoric).cwiseQuotient(stretch_squared);
    // S = Q diag(S_i) Q^T from the upper triangle, mirrored: exactly symmetric and a third cheaper.
    const Mat3& Q = principal.vectors;
    Mat3 result;
    for (int i = 0; i < 3; ++i)
      for (int j = i; j < 3; ++j) {
        result(i, j) = Q(i, 0) * principal_stress[0] * Q(j, 0) + Q(i, 1) * principal_stress[1] * Q(j, 1) +
                       Q(i, 2) * principal_stress[2] * Q(j, 2);
        result(j, i) = result(i, j);
      }
    // Not finite: an F so extreme that C has a round-off eigenvalue <= 0 or S overflows.
    if (!result.allFinite()) return false;
    S = result;
    return true;
  }

  void stress_batch(StressBatch& batch) const noexcept override {
    hyperelastic::ogden_stress_batch({half_alpha_, stress_factor_, volumetric_.bulk_modulus()}, batch);
  }

  json closed_form() const override {
    return {{"law", "ogden"}, {"mu", mu_}, {"alpha", alpha_}, {"D", D_}};
  }

  double energy(const Mat3& F) const noexcept override {
    double J;
    if (!hyperelastic::admissible(F, J)) return std::numeric_limits<double>::quiet_NaN();
    const Vec3 isochoric = isochoric_powers(symmetric_eigen3(F.transpose() * F).values, J);
    return energy_factor_ * (isochoric.sum() - 3.0) + volumetric_.energy(J);
  }

 private:
  // J^(-alpha/3) lambda_i^alpha = (J^(-2/3) lambda_i^2)^(alpha/2), from the eigenvalues lambda_i^2 of C:
  // one cube root and three powers instead of four powers.
  Vec3 isochoric_powers(const Vec3& stretch_squared, double J) const noexcept {
    const Vec3 bar = stretch_squared * hyperelastic::J_minus_two_thirds(J);
    return {std::pow(bar[0], half_alpha_), std::pow(bar[1], half_alpha_), std::pow(bar[2], half_alpha_)};
  }

  double mu_;
  double alpha_;
  double D_;
  hyperelastic::VolumetricPenalty volumetric_;
  double density_;
  double half_alpha_;
  double energy_factor_;  // 2 mu / alpha^2
  double stress_factor_;  // 2 mu / alpha
};

}  // namespace mtled

MTLED_PLUGIN(mtled::Material, mtled::OgdenMaterial)
