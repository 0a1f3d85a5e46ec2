// A compressible Mooney-Rivlin material, written as a third party would write one: the law once, in
// mooney_rivlin_law-inl.h, and here its parameters and the Material interface. The one-point stress() and energy()
// and the vectorised stress_batch() (mooney_rivlin_batch.cpp) are that one source, instantiated for a double and for
// a SIMD vector of integration points. The initial shear modulus is 2 (C10 + C01) and the bulk modulus 2/D.
#include "mooney_rivlin_law-inl.h"
#include "mtled/interfaces/material.hpp"
#include "mtled/law/one_point.hpp"
#include "mtled/plugin.hpp"

namespace example {

class MooneyRivlinMaterial final : public mtled::Material {
 public:
  // The one declaration: it drives scene validation, `mtled plugins --describe mooney_rivlin`, the JSON
  // Schema and the generated parameter reference; each parameter is bound to the member it fills.
  static void declare(mtled::ComponentDeclaration& d) {
    d.summary("Compressible Mooney-Rivlin hyperelastic material (example of an out-of-tree plugin).");
    d.number("c10").unit("Pa").positive().doc("first Mooney-Rivlin constant").to<&Settings::c10>();
    d.number("c01").unit("Pa").non_negative().defaults(0.0).doc("second Mooney-Rivlin constant").to<&Settings::c01>();
    d.number("D").unit("1/Pa").positive().doc("compressibility: bulk modulus K = 2/D").to<&Settings::D>();
    d.number("density").unit("kg/m^3").positive().defaults(1000.0).doc("mass density").to<&Settings::density>();
    d.example({{"c10", 300.0}, {"c01", 60.0}, {"D", 5.57738e-5}});
  }

  explicit MooneyRivlinMaterial(const mtled::Parameters& p)
      : settings_(p.read<Settings>()), law_{settings_.c10, settings_.c01, 1.0 / settings_.D} {}

  double density() const override { return settings_.density; }
  double p_wave_modulus() const override { return 2.0 * law_.inverse_D + 4.0 / 3.0 * 2.0 * (law_.c10 + law_.c01); }
  bool stress(const mtled::Mat3& F, mtled::Mat3& S) const noexcept override {
    return mtled::scalar::one_point_stress(law_, F, S);
  }
  double energy(const mtled::Mat3& F) const noexcept override { return mtled::scalar::one_point_energy(law_, F); }
  void stress_batch(mtled::StressBatch& batch) const noexcept override {
    mtled::mooney_rivlin_stress_batch(law_, batch);
  }

 private:
  struct Settings {
    double c10 = 0.0, c01 = 0.0, D = 0.0, density = 0.0;
  };
  Settings settings_;
  MooneyRivlinLaw law_;
};

}  // namespace example

MTLED_PLUGIN(mtled::Material, example::MooneyRivlinMaterial)
