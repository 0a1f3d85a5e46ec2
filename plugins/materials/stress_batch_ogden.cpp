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
  const DoubleTag d;
  const DoubleVec third = hn::Set(d, 1.0 / 3.0), two_thirds = hn::Set(d, 2.0 / 3.0);
  const DoubleVec half_alpha = hn::Set(d, k.half_alpha), stress_factor = hn::Set(d, k.stress_factor);
  for (int p = 0; p < StressBatch::kCapacity; p += static_cast<int>(hn::Lanes(d))) {
    const Mat3V F = load_matrix(d, batch.F, p);
    const DoubleVec J = determinant(F);
    const DoubleMask ok = admissible(d, F, J);
    const DoubleVec safe_J = hn::IfThenElse(ok, J, hn::Set(d, 1.0));  // refused lanes: a finite stand-in
    const SymmetricEigen3V principal = symmetric_eigen3(d, right_cauchy_green(F));
    // A round-off eigenvalue <= 0 gives NaN here and a refused lane below, as in the one-point code.
    DoubleVec log_stretch_squared[3];
    for (int i = 0; i < 3; ++i) log_stretch_squared[i] = hn::Log(d, principal.values[i]);
    // log J from the same logs (J^2 = det C, the eigenvalues' product): one log fewer, and the isochoric stretches'
    // product is 1 to round-off.
    const DoubleVec log_J = hn::Mul(
        hn::Set(d, 0.5), hn::Add(hn::Add(log_stretch_squared[0], log_stretch_squared[1]), log_stretch_squared[2]));
    DoubleVec isochoric[3], sum = hn::Zero(d);
    for (int i = 0; i < 3; ++i) {
      isochoric[i] = hn::Exp(d, hn::Mul(half_alpha, hn::NegMulAdd(two_thirds, log_J, log_stretch_squared[i])));
      sum = hn::Add(sum, isochoric[i]);
    }
    const DoubleVec J_dU_dJ = hn::Mul(hn::Mul(hn::Set(d, k.two_over_D), safe_J), hn::Sub(safe_J, hn::Set(d, 1.0)));
    const DoubleVec a = hn::NegMulAdd(stress_factor, hn::Mul(sum, third), J_dU_dJ);
    // 1 / lambda_i^2 from one division: the other two eigenvalues over their product with it (the divider is the
    // batch's narrowest unit).
    const DoubleVec* l = principal.values;
    const DoubleVec inverse_product = hn::Div(hn::Set(d, 1.0), hn::Mul(hn::Mul(l[0], l[1]), l[2]));
    const DoubleVec inverse[3] = {hn::Mul(hn::Mul(l[1], l[2]), inverse_product),
                                  hn::Mul(hn::Mul(l[0], l[2]), inverse_product),
                                  hn::Mul(hn::Mul(l[0], l[1]), inverse_product)};
    DoubleVec principal_stress[3];
    for (int i = 0; i < 3; ++i) principal_stress[i] = hn::Mul(hn::MulAdd(stress_factor, isochoric[i], a), inverse[i]);
    store_stress(d, spectral_sum(principal, principal_stress), ok, batch, p);
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
