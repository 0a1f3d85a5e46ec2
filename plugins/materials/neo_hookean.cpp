// Compressible neo-Hookean law: the paper's eq. (1) with alpha = 2 (its Table 1 note),
//   W = (mu/2)(J^(-2/3) tr C - 3) + (1/D)(J - 1)^2,
//   S = 2 dW/dC = mu J^(-2/3) (I - (tr C / 3) C^-1) + (2/D) J (J - 1) C^-1,
// using d(tr C)/dC = I and dJ/dC = (J/2) C^-1. Needs no eigen decomposition: C^-1 = F^-1 F^-T.
#include <cmath>
#include <limits>

#include "hyperelastic.hpp"
#include "mtled/interfaces/material.hpp"
#include "mtled/plugin.hpp"
#include "stress_batch.hpp"

namespace mtled {

class NeoHookeanMaterial final : public Material {
 public:
  static void declare(ComponentDeclaration& d) {
    d.summary("compressible neo-Hookean hyperelastic solid, W = (mu/2)(J^(-2/3) tr C - 3) + (1/D)(J - 1)^2 "
              "(the paper's eq. (1) with alpha = 2)");
    hyperelastic::declare_shear_modulus(d);
    hyperelastic::declare_compressibility(d);
    hyperelastic::declare_density(d);
    // The paper's neo-Hookean comparison material (Table 1, Material 4): mu = 1000 Pa, nu = 0.49.
    d.example({{"mu", 1000.0}, {"D", 4.02684e-5}, {"density", 1000.0}});
  }

  explicit NeoHookeanMaterial(const Parameters& p)
      : mu_(p.number("mu")), D_(p.number("D")), volumetric_(D_), density_(p.number("density")) {}

  double density() const override { return density_; }
  double p_wave_modulus() const override { return hyperelastic::p_wave_modulus(mu_, volumetric_); }

  bool stress(const Mat3& F, Mat3& S) const noexcept override {
    double J;
    if (!hyperelastic::admissible(F, J)) return false;
    const Mat3 F_inverse = F.inverse();
    const Mat3 C_inverse = F_inverse * F_inverse.transpose();  // bitwise symmetric: same products, same order
    const double shear = mu_ * hyperelastic::J_minus_two_thirds(J);
    // tr C / 3 is 1 exactly at F = I, so S(I) = 0 exactly.
    const double coefficient = volumetric_.J_dU_dJ(J) - shear * (F.squaredNorm() / 3.0);
    Mat3 result = coefficient * C_inverse;
    result.diagonal().array() += shear;
    if (!result.allFinite()) return false;  // an F so extreme that S overflows
    S = result;
    return true;
  }

  void stress_batch(StressBatch& batch) const noexcept override {
    hyperelastic::neo_hookean_stress_batch({mu_, volumetric_.bulk_modulus()}, batch);
  }

  json closed_form() const override {
    return {{"law", "neo_hookean"}, {"mu", mu_}, {"D", D_}};
  }

  double energy(const Mat3& F) const noexcept override {
    double J;
    if (!hyperelastic::admissible(F, J)) return std::numeric_limits<double>::quiet_NaN();
    return 0.5 * mu_ * (F.squaredNorm() * hyperelastic::J_minus_two_thirds(J) - 3.0) + volumetric_.energy(J);
  }

 private:
  double mu_;
  double D_;
  hyperelastic::VolumetricPenalty volumetric_;
  double density_;
};

}  // namespace mtled

MTLED_PLUGIN(mtled::Material, mtled::NeoHookeanMaterial)
