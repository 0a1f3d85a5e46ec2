// What the hyperelastic laws of the paper's eq. (1) share, in the arithmetic of mtled/law/arithmetic-inl.h (once per
// SIMD target, like the laws): the volumetric term U(J) = (1/D)(J - 1)^2. Its share of S is J U'(J) C^-1, and its
// small-strain bulk modulus is U''(1) = 2/D.

// Once per translation unit: the constants.
#ifndef MTLED_HYPERELASTIC_ONCE_
#define MTLED_HYPERELASTIC_ONCE_
namespace mtled::hyperelastic {
struct VolumetricPenalty {
  explicit VolumetricPenalty(double D) : inverse_D(1.0 / D), two_over_D(2.0 * inverse_D) {}
  double inverse_D;   // 1/D
  double two_over_D;  // the bulk modulus K = U''(1)
};
}  // namespace mtled::hyperelastic
#endif

// Once per SIMD target.
#if defined(MTLED_HYPERELASTIC_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef MTLED_HYPERELASTIC_INL_H_
#undef MTLED_HYPERELASTIC_INL_H_
#else
#define MTLED_HYPERELASTIC_INL_H_
#endif

#include "mtled/law/arithmetic-inl.h"

MTLED_LAW_BEGIN

template <class T>
MTLED_HOST_DEVICE inline T volumetric_energy(const hyperelastic::VolumetricPenalty& penalty, const T& J) {
  return ((J - T(1.0)) * (J - T(1.0))) * T(penalty.inverse_D);
}

// J U'(J) = (2/D) J (J - 1).
template <class T>
MTLED_HOST_DEVICE inline T J_dU_dJ(const hyperelastic::VolumetricPenalty& penalty, const T& J) {
  return (T(penalty.two_over_D) * J) * (J - T(1.0));
}

MTLED_LAW_END
#endif  // MTLED_HYPERELASTIC_INL_H_
