// Compressible neo-Hookean law, the paper's eq. (1) with alpha = 2: the plugin's parameters and the Material
// interface; the law itself (stress and energy, one source for the one-point, SIMD and GPU paths) is in
// neo_hookean_law-inl.h.
#include "hyperelastic.hpp"
#include "mtled/interfaces/material.hpp"
#include "mtled/law/one_point.hpp"
#include "mtled/plugin.hpp"
#include "neo_hookean_law-inl.h"

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
      : moduli_(p.read<hyperelastic::Moduli>()), law_(moduli_.mu, moduli_.D) {}

  double density() const override { return moduli_.density; }
  double p_wave_modulus() const override { return hyperelastic::p_wave_modulus(moduli_.mu, law_.volumetric); }
  bool stress(const Mat3& F, Mat3& S) const noexcept override { return scalar::one_point_stress(law_, F, S); }
  void stress_batch(StressBatch& batch) const noexcept override { neo_hookean_stress_batch(law_, batch); }
  double energy(const Mat3& F) const noexcept override { return scalar::one_point_energy(law_, F); }

#ifdef MTLED_DEVICE_LAWS
  DeviceLaw device_law() const override { return {&neo_hookean_device_stress_pass, &law_}; }
#endif

 private:
  hyperelastic::Moduli moduli_;
  NeoHookeanLaw law_;
};

}  // namespace mtled

MTLED_PLUGIN(mtled::Material, mtled::NeoHookeanMaterial)
