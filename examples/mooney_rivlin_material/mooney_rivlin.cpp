// A compressible Mooney-Rivlin material, written as a third party would write one:
//   W = C10 (I1bar - 3) + C01 (I2bar - 3) + (1/D)(J - 1)^2,
// with I1bar = J^(-2/3) tr C and I2bar = J^(-4/3) (tr(C)^2 - tr(C^2)) / 2. With C01 = 0 it is the neo-Hookean
// law with mu = 2 C10. The initial shear modulus is 2 (C10 + C01) and the bulk modulus 2/D.
#include <cmath>

#include "mtled/interfaces/material.hpp"
#include "mtled/plugin.hpp"

namespace example {

class MooneyRivlinMaterial final : public mtled::Material {
 public:
  // The one declaration: it drives scene validation, `mtled plugins --describe mooney_rivlin`, the JSON
  // Schema and the generated parameter reference.
  static void declare(mtled::ComponentDeclaration& d) {
    d.summary("Compressible Mooney-Rivlin hyperelastic material (example of an out-of-tree plugin).");
    d.number("c10").unit("Pa").positive().doc("first Mooney-Rivlin constant");
    d.number("c01").unit("Pa").non_negative().defaults(0.0).doc("second Mooney-Rivlin constant");
    d.number("D").unit("1/Pa").positive().doc("compressibility: bulk modulus K = 2/D");
    d.number("density").unit("kg/m^3").positive().defaults(1000.0).doc("mass density");
    d.example({{"c10", 300.0}, {"c01", 60.0}, {"D", 5.57738e-5}});
  }

  explicit MooneyRivlinMaterial(const mtled::Parameters& p)
      : c10_(p.number("c10")), c01_(p.number("c01")), d_(p.number("D")), density_(p.number("density")) {}

  double density() const override { return density_; }
  double p_wave_modulus() const override { return 2.0 / d_ + 4.0 / 3.0 * 2.0 * (c10_ + c01_); }

  bool stress(const mtled::Mat3& F, mtled::Mat3& S) const noexcept override {
    const double J = F.determinant();
    if (!(J > 0.0) || !std::isfinite(J)) return false;  // inverted or broken: refuse, never use |J|
    const mtled::Mat3 C = F.transpose() * F;
    const mtled::Mat3 C_inv = C.inverse();
    const mtled::Mat3 I = mtled::Mat3::Identity();
    const double I1 = C.trace();
    const double I2 = 0.5 * (I1 * I1 - (C * C).trace());
    const double j23 = std::pow(J, -2.0 / 3.0);
    // S = 2 dW/dC, with dI1bar/dC = J^(-2/3)(I - I1/3 C^-1), dI2bar/dC = J^(-4/3)(I1 I - C - 2/3 I2 C^-1).
    S = 2.0 * c10_ * j23 * (I - I1 / 3.0 * C_inv) + 2.0 * c01_ * j23 * j23 * (I1 * I - C - 2.0 / 3.0 * I2 * C_inv) +
        2.0 / d_ * J * (J - 1.0) * C_inv;
    return true;
  }

  double energy(const mtled::Mat3& F) const noexcept override {
    const double J = F.determinant();
    if (!(J > 0.0) || !std::isfinite(J)) return std::nan("");
    const mtled::Mat3 C = F.transpose() * F;
    const double I1 = C.trace();
    const double I2 = 0.5 * (I1 * I1 - (C * C).trace());
    const double j23 = std::pow(J, -2.0 / 3.0);
    return c10_ * (j23 * I1 - 3.0) + c01_ * (j23 * j23 * I2 - 3.0) + (J - 1.0) * (J - 1.0) / d_;
  }

 private:
  double c10_, c01_, d_, density_;
};

}  // namespace example

MTLED_PLUGIN(mtled::Material, example::MooneyRivlinMaterial)
