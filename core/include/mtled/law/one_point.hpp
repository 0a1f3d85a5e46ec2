#pragma once
// A law's one-point stress() and energy() for its Material class, from its single source (arithmetic-inl.h): the
// law's templates with T = double (in mtled::scalar), between Eigen's 3x3 matrices and the law's own.
#include "mtled/law/arithmetic-inl.h"
#include "mtled/types.hpp"

namespace mtled::scalar {

inline Matrix3<double> to_matrix3(const Mat3& a) {
  Matrix3<double> out;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) out.m[i][j] = a(i, j);
  return out;
}

// Material::stress(): false, S untouched, where F is inadmissible or S not finite.
template <class Law>
bool one_point_stress(const Law& law, const Mat3& F, Mat3& S) noexcept {
  const LawStress<double> result = evaluate_stress(law, to_matrix3(F));
  if (!result.admissible) return false;
  for (int i = 0; i < 3; ++i)
    for (int j = i; j < 3; ++j) S(i, j) = S(j, i) = result.S.m[i][j];
  return true;
}

// Material::energy(): NaN where F is inadmissible.
template <class Law>
double one_point_energy(const Law& law, const Mat3& F) noexcept {
  return evaluate_energy(law, to_matrix3(F));
}

}  // namespace mtled::scalar
