#pragma once
#include "mtled/law/device_stress_pass.hpp"
#include "mtled/parameters.hpp"
#include "mtled/types.hpp"

namespace mtled {

// Deformation gradients and stresses of up to kCapacity integration points, structure of arrays: component
// (i, j) of point p at F[3 i + j][p]. The force kernel fills every lane it does not use with F = I, so a
// vectorised law may compute all lanes and need not mask.
struct StressBatch {
  static constexpr int kCapacity = 8;
  int count = 0;
  alignas(64) double F[9][kCapacity];
  alignas(64) double S[9][kCapacity];  // second Piola-Kirchhoff stress, written by the law
  bool admissible[kCapacity];          // written by the law: false where stress() would return false

  Mat3 deformation_gradient(int p) const {
    Mat3 m;
    for (int c = 0; c < 9; ++c) m(c / 3, c % 3) = F[c][p];
    return m;
  }
  void set_deformation_gradient(int p, const Mat3& m) {
    for (int c = 0; c < 9; ++c) F[c][p] = m(c / 3, c % 3);
  }
  Mat3 stress(int p) const {
    Mat3 m;
    for (int c = 0; c < 9; ++c) m(c / 3, c % 3) = S[c][p];
    return m;
  }
  void set_stress(int p, const Mat3& m) {
    for (int c = 0; c < 9; ++c) S[c][p] = m(c / 3, c % 3);
  }
};

// A hyperelastic constitutive law in the Total Lagrangian form: second Piola-Kirchhoff stress S(F) and
// strain energy W(F) per unit reference volume. Implementations must be thread-safe and must refuse
// (return false / NaN) an inadmissible F: J = det F <= 0 or non-finite entries, never hide it with |J|.
class Material {
 public:
  static constexpr Category category = Category::material;
  virtual ~Material();

  virtual double density() const = 0;  // kg/m^3
  // lambda + 2 mu of the material linearised at F = I (Pa): the dilatational wave speed for the stable step.
  virtual double p_wave_modulus() const = 0;
  virtual bool stress(const Mat3& F, Mat3& S) const noexcept = 0;
  virtual double energy(const Mat3& F) const noexcept = 0;
  // The stresses of a batch of points, which the force kernel calls. The default calls stress() per point; a law
  // written once in the arithmetic of mtled/law/arithmetic-inl.h gets a vectorised one from the same source
  // (mtled/law/stress_batch-inl.h), which the material conformance suite checks against stress().
  virtual void stress_batch(StressBatch& batch) const noexcept;
  // The law's code for a GPU backend, compiled into the plugin from the same source (mtled/law/device_stress_pass.cuh).
  // Empty (the default) where the plugin has none: such a backend then refuses the scene, naming the material.
  virtual DeviceLaw device_law() const;
};

}  // namespace mtled
