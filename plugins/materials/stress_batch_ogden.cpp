// Ogden stress for a batch of integration points (stress_batch.hpp), lane by lane the arithmetic of
// OgdenMaterial::stress() in ogden.cpp: principal stretches from the eigen decomposition of C, then
//   S_i = (a + b' J^(-alpha/3) lambda_i^alpha) / lambda_i^2,  b' = 2 mu / alpha,
//   a = (2/D) J (J - 1) - b' sum_j J^(-alpha/3) lambda_j^alpha / 3,
// with the powers as exp((alpha/2) (log lambda_i^2 - (2/3) log J)): one log per stretch and one exp instead of
// a pow and a cube root, and log J = (1/2) sum_i log lambda_i^2.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "stress_batch_ogden.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

#include "hyperelastic_simd-inl.h"
#include "stress_batch.hpp"

HWY_BEFORE_NAMESPACE();
namespace mtled::HWY_NAMESPACE {

void OgdenStressBatch(const hyperelastic::OgdenConstants& k, StressBatch& batch) {
  const PointVec third = set(1.0 / 3.0), two_thirds = set(2.0 / 3.0);
  const PointVec half_alpha = set(k.half_alpha), stress_factor = set(k.stress_factor);
  for (int p = 0; p < StressBatch::kCapacity; p += kPassLanes) {
    const Mat3V F = load_matrix(batch.F, p);
    const PointVec J = determinant(F);
    const PointMask ok = admissible(F, J);
    const PointVec safe_J = select(ok, J, set(1.0));  // refused lanes: a finite stand-in
    const SymmetricEigen3V principal = symmetric_eigen3(right_cauchy_green(F));
    // A round-off eigenvalue <= 0 gives NaN here and a refused lane below, as in the one-point code.
    PointVec log_stretch_squared[3];
    for (int i = 0; i < 3; ++i) log_stretch_squared[i] = log(principal.values[i]);
    // log J from the same logs (J^2 = det C, the eigenvalues' product): one log fewer, and the isochoric stretches'
    // product is 1 to round-off.
    const PointVec log_J =
        mul(set(0.5), add(add(log_stretch_squared[0], log_stretch_squared[1]), log_stretch_squared[2]));
    PointVec isochoric[3], sum = zeros();
    for (int i = 0; i < 3; ++i) {
      isochoric[i] = exp(mul(half_alpha, neg_mul_add(two_thirds, log_J, log_stretch_squared[i])));
      sum = add(sum, isochoric[i]);
    }
    const PointVec J_dU_dJ = mul(mul(set(k.two_over_D), safe_J), sub(safe_J, set(1.0)));
    const PointVec a = neg_mul_add(stress_factor, mul(sum, third), J_dU_dJ);
    // 1 / lambda_i^2 from one division: the other two eigenvalues over their product with it (the divider is the
    // batch's narrowest unit).
    const PointVec* l = principal.values;
    const PointVec inverse_product = div(set(1.0), mul(mul(l[0], l[1]), l[2]));
    const PointVec inverse[3] = {mul(mul(l[1], l[2]), inverse_product), mul(mul(l[0], l[2]), inverse_product),
                                 mul(mul(l[0], l[1]), inverse_product)};
    PointVec principal_stress[3];
    for (int i = 0; i < 3; ++i) principal_stress[i] = mul(mul_add(stress_factor, isochoric[i], a), inverse[i]);
    store_stress(spectral_sum(principal, principal_stress), ok, batch, p);
  }
}

}  // namespace mtled::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace mtled::hyperelastic {
HWY_EXPORT(OgdenStressBatch);
void ogden_stress_batch(const OgdenConstants& constants, StressBatch& batch) noexcept {
  HWY_DYNAMIC_DISPATCH(OgdenStressBatch)(constants, batch);
}
}  // namespace mtled::hyperelastic
#endif
