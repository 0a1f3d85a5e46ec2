#pragma once
// The vectorised stress_batch() of the laws here (stress_batch_*.cpp): one SIMD lane per integration point,
// dispatched at run time to the best instruction set the CPU has (Google Highway). Each agrees with its law's
// one-point stress() to round-off; tests/materials checks them against it on every instruction set.
#include "mtled/interfaces/material.hpp"

namespace mtled::hyperelastic {

// Ogden (ogden.cpp): S_i = a / lambda_i^2 + b lambda_i^(alpha - 2) along the eigenvectors of C.
struct OgdenConstants {
  double half_alpha;     // alpha / 2
  double stress_factor;  // 2 mu / alpha
  double two_over_D;     // J U'(J) = (2/D) J (J - 1)
};
void ogden_stress_batch(const OgdenConstants& constants, StressBatch& batch) noexcept;

// Neo-Hookean (neo_hookean.cpp): S = mu J^(-2/3) (I - (tr C / 3) C^-1) + (2/D) J (J - 1) C^-1.
struct NeoHookeanConstants {
  double mu;
  double two_over_D;
};
void neo_hookean_stress_batch(const NeoHookeanConstants& constants, StressBatch& batch) noexcept;

}  // namespace mtled::hyperelastic
