// One-term compressible Ogden law, the paper's eq. (1):
//   W = (2 mu / alpha^2)(J^(-alpha/3) sum_i lambda_i^alpha - 3) + (1/D)(J - 1)^2,
// written once (mtled/law/arithmetic-inl.h) for the one-point stress, the SIMD batch and the GPU.
// Stress in principal form (as for any isotropic law of the principal stretches, e.g. Holzapfel, Nonlinear Solid
// Mechanics, 2000, sec. 6.5). For an isotropic W(lambda_1, lambda_2, lambda_3), S_i = (1/lambda_i) dW/dlambda_i
// along the eigenvectors of C. With dJ/dlambda_i = J / lambda_i,
//   dW/dlambda_i = (2 mu / alpha) J^(-alpha/3) (lambda_i^(alpha-1) - sum_j lambda_j^alpha / (3 lambda_i))
//                  + (2/D)(J - 1) J / lambda_i,
// so with b = (2 mu / alpha) J^(-alpha/3) and a = (2/D) J (J - 1) - (b/3) sum_j lambda_j^alpha,
//   S_i = a / lambda_i^2 + b lambda_i^(alpha - 2),   S = Q diag(S_i) Q^T,   C = Q diag(lambda_i^2) Q^T.
// Equal stretches cause no 0/0 here; what needs care is the eigen decomposition itself (symmetric_eigen3).
// alpha = 2 gives b = mu J^(-2/3) and S = b I + a C^-1: the neo-Hookean law. The small-strain shear modulus is
// (2 mu / alpha^2) alpha^2 / 2 = mu.

#include "hyperelastic-inl.h"

// Once per translation unit: the constants, and the law's SIMD and device entry points.
#ifndef MTLED_OGDEN_LAW_ONCE_
#define MTLED_OGDEN_LAW_ONCE_
namespace mtled {
struct OgdenLaw {
  OgdenLaw(double mu, double alpha, double D)
      : half_alpha(0.5 * alpha),
        stress_factor(2.0 * mu / alpha),
        energy_factor(2.0 * mu / (alpha * alpha)),
        volumetric(D) {}
  double half_alpha;     // alpha / 2
  double stress_factor;  // 2 mu / alpha
  double energy_factor;  // 2 mu / alpha^2
  hyperelastic::VolumetricPenalty volumetric;
};
struct StressBatch;
struct DeviceStressPass;
void ogden_stress_batch(const OgdenLaw& law, StressBatch& batch) noexcept;    // ogden_batch.cpp
int ogden_device_stress_pass(const void* law, const DeviceStressPass& pass);  // ogden_device.cu, with CUDA
}  // namespace mtled
#endif

// Once per SIMD target.
#if defined(MTLED_OGDEN_LAW_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef MTLED_OGDEN_LAW_INL_H_
#undef MTLED_OGDEN_LAW_INL_H_
#else
#define MTLED_OGDEN_LAW_INL_H_
#endif

MTLED_LAW_BEGIN

// J^(-alpha/3) lambda_i^alpha of the eigenvalues lambda_i^2 of C, and their sum: the powers as
// exp((alpha/2) (log lambda_i^2 - (2/3) log J)), one log per stretch and one exp instead of a pow and a cube root,
// with log J = (1/2) sum_i log lambda_i^2 (J^2 = det C): one log fewer, and the isochoric stretches' product is 1
// to round-off. A round-off eigenvalue <= 0 gives NaN here and a refused point.
template <class T>
MTLED_HOST_DEVICE inline T isochoric_powers(const OgdenLaw& law, const T (&stretch_squared)[3], T (&isochoric)[3]) {
  T log_stretch_squared[3];
  for (int i = 0; i < 3; ++i) log_stretch_squared[i] = log(stretch_squared[i]);
  const T log_J = T(0.5) * (log_stretch_squared[0] + log_stretch_squared[1] + log_stretch_squared[2]);
  T sum(0.0);
  for (int i = 0; i < 3; ++i) {
    isochoric[i] = exp(T(law.half_alpha) * neg_mul_add(T(2.0 / 3.0), log_J, log_stretch_squared[i]));
    sum = sum + isochoric[i];
  }
  return sum;
}

template <class T>
MTLED_HOST_DEVICE inline Matrix3<T> stress(const OgdenLaw& law, const Matrix3<T>& F, const T& J) {
  const SymmetricEigen3<T> principal = symmetric_eigen3(right_cauchy_green(F));
  const T* l = principal.values;
  T isochoric[3];
  const T sum = isochoric_powers(law, principal.values, isochoric);
  const T stress_factor(law.stress_factor);
  // sum / 3 is 1 exactly at F = I, so a = -2 mu / alpha there and S(I) = 0 exactly.
  const T a = neg_mul_add(stress_factor, sum * T(1.0 / 3.0), J_dU_dJ(law.volumetric, J));
  // 1 / lambda_i^2 from one division: the other two eigenvalues over their product with it (the divider is a SIMD
  // batch's narrowest unit).
  const T inverse_product = T(1.0) / ((l[0] * l[1]) * l[2]);
  const T inverse[3] = {(l[1] * l[2]) * inverse_product, (l[0] * l[2]) * inverse_product,
                        (l[0] * l[1]) * inverse_product};
  T principal_stress[3];
  for (int i = 0; i < 3; ++i) principal_stress[i] = mul_add(stress_factor, isochoric[i], a) * inverse[i];
  return spectral_sum(principal, principal_stress);
}

template <class T>
MTLED_HOST_DEVICE inline T energy(const OgdenLaw& law, const Matrix3<T>& F, const T& J) {
  T isochoric[3];
  const T sum = isochoric_powers(law, symmetric_eigen3(right_cauchy_green(F)).values, isochoric);
  return T(law.energy_factor) * (sum - T(3.0)) + volumetric_energy(law.volumetric, J);
}

MTLED_LAW_END
#endif  // MTLED_OGDEN_LAW_INL_H_
