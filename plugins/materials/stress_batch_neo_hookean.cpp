// Neo-Hookean stress for a batch of integration points (stress_batch.hpp), lane by lane the arithmetic of
// NeoHookeanMaterial::stress() in neo_hookean.cpp:
//   S = shear I + (J U'(J) - shear |F|^2 / 3) C^-1,  shear = mu J^(-2/3),  C^-1 = F^-1 F^-T,
// with F^-1 = adj(F) / J and J^(-2/3) = exp(-(2/3) log J).
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "stress_batch_neo_hookean.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

#include "hyperelastic_simd-inl.h"
#include "stress_batch.hpp"

HWY_BEFORE_NAMESPACE();
namespace mtled::HWY_NAMESPACE {

void NeoHookeanStressBatch(const hyperelastic::NeoHookeanConstants& k, StressBatch& batch) {
  const PointVec one = set(1.0);
  for (int p = 0; p < StressBatch::kCapacity; p += kPassLanes) {
    const Mat3V F = load_matrix(batch.F, p);
    const PointVec J = determinant(F);
    const PointMask ok = admissible(F, J);
    const PointVec safe_J = select(ok, J, one);
    const PointVec inverse_J = div(one, safe_J);
    // F^-1 = adj(F) / J: (F^-1)_ij = cofactor_ji / J.
    const auto& f = F.m;
    Mat3V Fi;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        const int r0 = (j + 1) % 3, r1 = (j + 2) % 3, c0 = (i + 1) % 3, c1 = (i + 2) % 3;
        Fi.m[i][j] = mul(sub(mul(f[r0][c0], f[r1][c1]), mul(f[r0][c1], f[r1][c0])), inverse_J);
      }
    PointVec squared_norm = zeros();
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) squared_norm = mul_add(f[i][j], f[i][j], squared_norm);
    const PointVec shear = mul(set(k.mu), exp(mul(set(-2.0 / 3.0), log(safe_J))));
    const PointVec J_dU_dJ = mul(mul(set(k.two_over_D), safe_J), sub(safe_J, one));
    // tr C / 3 is 1 exactly at F = I, so S(I) = 0 exactly.
    const PointVec coefficient = neg_mul_add(shear, div(squared_norm, set(3.0)), J_dU_dJ);
    Mat3V S;
    for (int i = 0; i < 3; ++i)
      for (int j = i; j < 3; ++j) {
        const PointVec C_inverse =
            mul_add(Fi.m[i][2], Fi.m[j][2], mul_add(Fi.m[i][1], Fi.m[j][1], mul(Fi.m[i][0], Fi.m[j][0])));
        S.m[i][j] = mul(coefficient, C_inverse);
        if (i == j) S.m[i][j] = add(S.m[i][j], shear);
      }
    store_stress(S, ok, batch, p);
  }
}

}  // namespace mtled::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace mtled::hyperelastic {
HWY_EXPORT(NeoHookeanStressBatch);
void neo_hookean_stress_batch(const NeoHookeanConstants& constants, StressBatch& batch) noexcept {
  HWY_DYNAMIC_DISPATCH(NeoHookeanStressBatch)(constants, batch);
}
}  // namespace mtled::hyperelastic
#endif
