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
  const DoubleTag d;
  const DoubleVec one = hn::Set(d, 1.0);
  for (int p = 0; p < StressBatch::kCapacity; p += static_cast<int>(hn::Lanes(d))) {
    const Mat3V F = load_matrix(d, batch.F, p);
    const DoubleVec J = determinant(F);
    const DoubleMask ok = admissible(d, F, J);
    const DoubleVec safe_J = hn::IfThenElse(ok, J, one);
    const DoubleVec inverse_J = hn::Div(one, safe_J);
    // F^-1 = adj(F) / J: (F^-1)_ij = cofactor_ji / J.
    const auto& f = F.m;
    Mat3V Fi;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        const int r0 = (j + 1) % 3, r1 = (j + 2) % 3, c0 = (i + 1) % 3, c1 = (i + 2) % 3;
        Fi.m[i][j] = hn::Mul(hn::Sub(hn::Mul(f[r0][c0], f[r1][c1]), hn::Mul(f[r0][c1], f[r1][c0])), inverse_J);
      }
    DoubleVec squared_norm = hn::Zero(d);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) squared_norm = hn::MulAdd(f[i][j], f[i][j], squared_norm);
    const DoubleVec shear = hn::Mul(hn::Set(d, k.mu), hn::Exp(d, hn::Mul(hn::Set(d, -2.0 / 3.0), hn::Log(d, safe_J))));
    const DoubleVec J_dU_dJ = hn::Mul(hn::Mul(hn::Set(d, k.two_over_D), safe_J), hn::Sub(safe_J, one));
    // tr C / 3 is 1 exactly at F = I, so S(I) = 0 exactly.
    const DoubleVec coefficient = hn::NegMulAdd(shear, hn::Div(squared_norm, hn::Set(d, 3.0)), J_dU_dJ);
    Mat3V S;
    for (int i = 0; i < 3; ++i)
      for (int j = i; j < 3; ++j) {
        const DoubleVec C_inverse =
            hn::MulAdd(Fi.m[i][2], Fi.m[j][2], hn::MulAdd(Fi.m[i][1], Fi.m[j][1], hn::Mul(Fi.m[i][0], Fi.m[j][0])));
        S.m[i][j] = hn::Mul(coefficient, C_inverse);
        if (i == j) S.m[i][j] = hn::Add(S.m[i][j], shear);
      }
    store_stress(d, S, ok, batch, p);
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
