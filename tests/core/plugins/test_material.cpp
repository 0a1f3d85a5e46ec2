// A minimal linear material used only to exercise the plugin loader (built several times with different
// compile definitions by tests/core/CMakeLists.txt).
#include <stdexcept>

#include "mtled/interfaces/material.hpp"
#include "mtled/plugin.hpp"

namespace mtled {

class TestMaterial final : public Material {
 public:
  static void declare(ComponentDeclaration& d) {
    d.summary("test only");
    d.number("modulus").unit("Pa").positive().defaults(1000.0).doc("test modulus").to<&Settings::modulus>();
  }
  explicit TestMaterial(const Parameters& p) : modulus_(p.read<Settings>().modulus) {
#ifdef MTLED_TEST_THROW_IN_CONSTRUCTOR
    throw std::runtime_error("deliberate failure inside the plugin's constructor");
#endif
  }
  double density() const override { return 1000.0; }
  double p_wave_modulus() const override { return modulus_; }
  bool stress(const Mat3& F, Mat3& S) const noexcept override {
    S = 0.5 * modulus_ * (F.transpose() * F - Mat3::Identity());
    return true;
  }
  double energy(const Mat3&) const noexcept override { return 0.0; }

 private:
  struct Settings {
    double modulus = 0.0;
  };
  double modulus_;
};

}  // namespace mtled

MTLED_PLUGIN(mtled::Material, mtled::TestMaterial)
