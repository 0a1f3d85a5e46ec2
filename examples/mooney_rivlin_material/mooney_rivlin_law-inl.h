// A compressible Mooney-Rivlin law, written once for every path that evaluates it (the one-point stress, the SIMD
// batch, a GPU) in the arithmetic of mtled/law/arithmetic-inl.h:
//   W = C10 (I1bar - 3) + C01 (I2bar - 3) + (1/D)(J - 1)^2,
// with I1bar = J^(-2/3) tr C and I2bar = J^(-4/3) (tr(C)^2 - tr(C^2)) / 2. With C01 = 0 it is the neo-Hookean law
// with mu = 2 C10. S = 2 dW/dC with dI1bar/dC = J^(-2/3)(I - I1/3 C^-1), dI2bar/dC = J^(-4/3)(I1 I - C - 2/3 I2 C^-1)
// and dJ/dC = (J/2) C^-1.
//
// The header is included once per SIMD target by mooney_rivlin_batch.cpp (Highway's per-target include guard below)
// and once by mooney_rivlin.cpp.

// Once per translation unit: the law's constants and its SIMD entry point.
#ifndef MOONEY_RIVLIN_LAW_ONCE_
#define MOONEY_RIVLIN_LAW_ONCE_
namespace example {
struct MooneyRivlinLaw {
  double c10, c01, inverse_D;
};
}  // namespace example
namespace mtled {
struct StressBatch;
// mooney_rivlin_batch.cpp: the law's stress_batch() on the best instruction set of the CPU.
void mooney_rivlin_stress_batch(const example::MooneyRivlinLaw& law, StressBatch& batch) noexcept;
}  // namespace mtled
#endif

// Once per SIMD target.
#if defined(MOONEY_RIVLIN_LAW_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef MOONEY_RIVLIN_LAW_INL_H_
#undef MOONEY_RIVLIN_LAW_INL_H_
#else
#define MOONEY_RIVLIN_LAW_INL_H_
#endif

#include "mtled/law/arithmetic-inl.h"

MTLED_LAW_BEGIN

// The invariants I1 = tr C and I2 = (I1^2 - tr C^2) / 2 of C (upper triangle).
template <class T>
MTLED_HOST_DEVICE inline void invariants(const Matrix3<T>& C, T& I1, T& I2) {
  const auto& c = C.m;
  I1 = c[0][0] + c[1][1] + c[2][2];
  const T trace_C2 = c[0][0] * c[0][0] + c[1][1] * c[1][1] + c[2][2] * c[2][2] +
                     T(2.0) * (c[0][1] * c[0][1] + c[0][2] * c[0][2] + c[1][2] * c[1][2]);
  I2 = T(0.5) * (I1 * I1 - trace_C2);
}

template <class T>
MTLED_HOST_DEVICE inline Matrix3<T> stress(const example::MooneyRivlinLaw& law, const Matrix3<T>& F, const T& J) {
  const Matrix3<T> C = right_cauchy_green(F), C_inverse = inverse_right_cauchy_green(F, J);
  T I1, I2;
  invariants(C, I1, I2);
  const T j23 = exp(T(-2.0 / 3.0) * log(J));  // J^(-2/3)
  const T a = T(2.0 * law.c10) * j23, b = T(2.0 * law.c01) * (j23 * j23);
  const T on_C_inverse = T(2.0 * law.inverse_D) * J * (J - T(1.0)) - a * I1 / T(3.0) - b * T(2.0 / 3.0) * I2;
  Matrix3<T> S;
  for (int i = 0; i < 3; ++i)
    for (int j = i; j < 3; ++j) {
      S.m[i][j] = on_C_inverse * C_inverse.m[i][j] - b * C.m[i][j];
      if (i == j) S.m[i][j] = S.m[i][j] + a + b * I1;
    }
  return S;
}

template <class T>
MTLED_HOST_DEVICE inline T energy(const example::MooneyRivlinLaw& law, const Matrix3<T>& F, const T& J) {
  T I1, I2;
  invariants(right_cauchy_green(F), I1, I2);
  const T j23 = exp(T(-2.0 / 3.0) * log(J));
  return T(law.c10) * (j23 * I1 - T(3.0)) + T(law.c01) * (j23 * j23 * I2 - T(3.0)) +
         (J - T(1.0)) * (J - T(1.0)) * T(law.inverse_D);
}

MTLED_LAW_END
#endif  // MOONEY_RIVLIN_LAW_INL_H_
