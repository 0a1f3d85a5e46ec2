// One-term compressible Ogden law, the paper's eq. (1): the plugin's parameters and the Material interface; the
// law itself (stress and energy, one source for the one-point, SIMD and GPU paths) is in ogden_law-inl.h.
#include "hyperelastic.hpp"
#include "mtled/interfaces/material.hpp"
#include "mtled/law/one_point.hpp"
#include "mtled/plugin.hpp"
#include "ogden_law-inl.h"

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
        .doc(
            "Ogden exponent on the principal stretches; it sets how the material stiffens: 2 is "
            "neo-Hookean, negative values stiffen more in compression; Sylgard 527 gel and brain tissue "
            "fits: about -1.3 to -4.7")
        .to<&Exponent::alpha>();
    hyperelastic::declare_compressibility(d);
    hyperelastic::declare_density(d);
    // Sylgard 527 gel, the paper's section 2.2.2 and Table 1 (Material 2): nu = 0.49.
    d.example({{"mu", 722.0}, {"alpha", -1.3}, {"D", 5.57738e-5}, {"density", 1000.0}});
  }

  explicit OgdenMaterial(const Parameters& p)
      : moduli_(p.read<hyperelastic::Moduli>()), law_(moduli_.mu, p.read<Exponent>().alpha, moduli_.D) {}

  double density() const override { return moduli_.density; }
  double p_wave_modulus() const override { return hyperelastic::p_wave_modulus(moduli_.mu, law_.volumetric); }
  bool stress(const Mat3& F, Mat3& S) const noexcept override { return scalar::one_point_stress(law_, F, S); }
  void stress_batch(StressBatch& batch) const noexcept override { ogden_stress_batch(law_, batch); }
  double energy(const Mat3& F) const noexcept override { return scalar::one_point_energy(law_, F); }

#ifdef MTLED_DEVICE_LAWS
  DeviceLaw device_law() const override { return {&ogden_device_stress_pass, &law_}; }
#endif

 private:
  struct Exponent {
    double alpha = 0.0;
  };
  hyperelastic::Moduli moduli_;
  OgdenLaw law_;
};

}  // namespace mtled

MTLED_PLUGIN(mtled::Material, mtled::OgdenMaterial)
