// Compressible neo-Hookean law: the paper's eq. (1) with alpha = 2 (its Table 1 note),
//   W = (mu/2)(J^(-2/3) tr C - 3) + (1/D)(J - 1)^2,
//   S = 2 dW/dC = mu J^(-2/3) (I - (tr C / 3) C^-1) + (2/D) J (J - 1) C^-1,
// using d(tr C)/dC = I and dJ/dC = (J/2) C^-1; written once (mtled/law/arithmetic-inl.h) for the one-point stress,
// the SIMD batch and the GPU. Needs no eigen decomposition: C^-1 = F^-1 F^-T with F^-1 = adj(F) / J, and
// J^(-2/3) = exp(-(2/3) log J).
#include "hyperelastic-inl.h"

// Once per translation unit: the constants, and the law's SIMD and device entry points.
#ifndef MTLED_NEO_HOOKEAN_LAW_ONCE_
#define MTLED_NEO_HOOKEAN_LAW_ONCE_
namespace mtled {
struct NeoHookeanLaw {
  NeoHookeanLaw(double shear_modulus, double D) : mu(shear_modulus), volumetric(D) {}
  double mu;
  hyperelastic::VolumetricPenalty volumetric;
};
struct StressBatch;
struct DeviceStressPass;
void neo_hookean_stress_batch(const NeoHookeanLaw& law, StressBatch& batch) noexcept;  // neo_hookean_batch.cpp
int neo_hookean_device_stress_pass(const void* law, const DeviceStressPass& pass);  // neo_hookean_device.cu, with CUDA
}  // namespace mtled
#endif

// Once per SIMD target.
#if defined(MTLED_NEO_HOOKEAN_LAW_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef MTLED_NEO_HOOKEAN_LAW_INL_H_
#undef MTLED_NEO_HOOKEAN_LAW_INL_H_
#else
#define MTLED_NEO_HOOKEAN_LAW_INL_H_
#endif

MTLED_LAW_BEGIN

// |F|^2 = tr C.
template <class T>
MTLED_HOST_DEVICE inline T squared_norm(const Matrix3<T>& F) {
  T sum(0.0);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) sum = mul_add(F.m[i][j], F.m[i][j], sum);
  return sum;
}

// J^(-2/3), which makes tr C isochoric.
template <class T>
MTLED_HOST_DEVICE inline T J_minus_two_thirds(const T& J) {
  return exp(T(-2.0 / 3.0) * log(J));
}

template <class T>
MTLED_HOST_DEVICE inline Matrix3<T> stress(const NeoHookeanLaw& law, const Matrix3<T>& F, const T& J) {
  const Matrix3<T> C_inverse = inverse_right_cauchy_green(F, J);
  const T shear = T(law.mu) * J_minus_two_thirds(J);
  // tr C / 3 is 1 exactly at F = I, so S(I) = 0 exactly.
  const T coefficient = neg_mul_add(shear, squared_norm(F) / T(3.0), J_dU_dJ(law.volumetric, J));
  Matrix3<T> S;
  for (int i = 0; i < 3; ++i)
    for (int j = i; j < 3; ++j)
      S.m[i][j] = i == j ? coefficient * C_inverse.m[i][j] + shear : coefficient * C_inverse.m[i][j];
  return S;
}

template <class T>
MTLED_HOST_DEVICE inline T energy(const NeoHookeanLaw& law, const Matrix3<T>& F, const T& J) {
  return T(0.5 * law.mu) * (J_minus_two_thirds(J) * squared_norm(F) - T(3.0)) + volumetric_energy(law.volumetric, J);
}

MTLED_LAW_END
#endif  // MTLED_NEO_HOOKEAN_LAW_INL_H_
