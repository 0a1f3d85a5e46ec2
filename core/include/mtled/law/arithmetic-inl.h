// The arithmetic a hyperelastic law is written in once, as templates over its scalar type T, and compiled for
// every path that evaluates stresses: T = double for the one-point stress() and energy() (host, one_point.hpp) and
// for a GPU's stress pass (CUDA device code, device_stress_pass.cuh); T = a vector of SIMD lanes, one integration
// point per lane, for stress_batch() (stress_batch-inl.h). A law's code therefore has no branches on values: it
// chooses with select(mask, a, b) and compares with lt/le/gt/ge/eq/ne, which give a bool for double and a lane mask
// for a vector. Arithmetic is + - * / and these functions: mul_add, neg_mul_add, sqrt, exp, log, acos, cos, abs,
// min, max, copy_sign; constants are written T(value).
//
// Here: that vocabulary for double, the 3x3 matrices of such scalars, what the laws share (det F, the admissibility
// of F, C = F^T F, the symmetric eigensolver for laws of the principal stretches, S = Q diag(s) Q^T) and the
// evaluation of a law.
//
// Like a law's own header, this one is included once per SIMD target in a Highway translation unit (its code must
// be compiled with each target's instruction set, which a template defined once outside the target's region would
// not be), and once elsewhere: hence Highway's per-target include guard, and MTLED_LAW_BEGIN / MTLED_LAW_END, which
// open the namespace of the target being compiled (mtled::N_AVX2, ...) or, without Highway, mtled::scalar.

// Once per translation unit.
#ifndef MTLED_LAW_ARITHMETIC_ONCE_
#define MTLED_LAW_ARITHMETIC_ONCE_
#include <cfloat>
#include <cmath>
#include <type_traits>
#include <utility>

#include "mtled/host_device.hpp"

namespace mtled::law_constants {
constexpr double kPi = 3.14159265358979323846;  // std::numbers::pi, which CUDA's C++17 lacks
}

// MTLED_LAW_SIMD is defined by stress_batch-inl.h, which a Highway translation unit includes before any law.
#ifdef MTLED_LAW_SIMD
#define MTLED_LAW_BEGIN   \
  HWY_BEFORE_NAMESPACE(); \
  namespace mtled::HWY_NAMESPACE {
#define MTLED_LAW_END \
  }                   \
  HWY_AFTER_NAMESPACE();
#else
#define MTLED_LAW_BEGIN namespace mtled::scalar {
#define MTLED_LAW_END }
#endif

#ifndef MTLED_LAW_SIMD
namespace mtled::scalar {
// ---- double: the vocabulary ---------------------------------------------------------------------------------------
// The global C functions: on the host the C library's, in CUDA device code the device's own of the same names.

MTLED_HOST_DEVICE inline double mul_add(double a, double b, double c) { return ::fma(a, b, c); }       // a b + c
MTLED_HOST_DEVICE inline double neg_mul_add(double a, double b, double c) { return ::fma(-a, b, c); }  // c - a b
MTLED_HOST_DEVICE inline double sqrt(double a) { return ::sqrt(a); }
MTLED_HOST_DEVICE inline double exp(double a) { return ::exp(a); }
MTLED_HOST_DEVICE inline double log(double a) { return ::log(a); }
MTLED_HOST_DEVICE inline double acos(double a) { return ::acos(a); }
MTLED_HOST_DEVICE inline double cos(double a) { return ::cos(a); }
MTLED_HOST_DEVICE inline double abs(double a) { return ::fabs(a); }
MTLED_HOST_DEVICE inline double min(double a, double b) { return ::fmin(a, b); }
MTLED_HOST_DEVICE inline double max(double a, double b) { return ::fmax(a, b); }
MTLED_HOST_DEVICE inline double copy_sign(double a, double b) { return ::copysign(a, b); }

MTLED_HOST_DEVICE inline bool eq(double a, double b) { return a == b; }
MTLED_HOST_DEVICE inline bool ne(double a, double b) { return a != b; }
MTLED_HOST_DEVICE inline bool lt(double a, double b) { return a < b; }
MTLED_HOST_DEVICE inline bool le(double a, double b) { return a <= b; }
MTLED_HOST_DEVICE inline bool gt(double a, double b) { return a > b; }
MTLED_HOST_DEVICE inline bool ge(double a, double b) { return a >= b; }
MTLED_HOST_DEVICE inline bool both(bool a, bool b) { return a && b; }
MTLED_HOST_DEVICE inline bool and_not(bool a, bool b) { return !a && b; }  // (not a) and b
MTLED_HOST_DEVICE inline bool negate(bool a) { return !a; }
MTLED_HOST_DEVICE inline double select(bool m, double a, double b) { return m ? a : b; }
MTLED_HOST_DEVICE inline double zero_unless(bool m, double a) { return m ? a : 0.0; }
}  // namespace mtled::scalar
#endif
#endif  // MTLED_LAW_ARITHMETIC_ONCE_

// Once per SIMD target (Highway's per-target include guard; without Highway, a plain include guard).
#if defined(MTLED_LAW_ARITHMETIC_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef MTLED_LAW_ARITHMETIC_INL_H_
#undef MTLED_LAW_ARITHMETIC_INL_H_
#else
#define MTLED_LAW_ARITHMETIC_INL_H_
#endif

MTLED_LAW_BEGIN
// The mask type of T: what its comparisons give.
template <class T>
using MaskOf = decltype(gt(std::declval<T>(), std::declval<T>()));

// ---- 3x3 matrices and 3-vectors of T --------------------------------------------------------------------------

template <class T>
struct Matrix3 {
  T m[3][3];
};
template <class T>
struct Vector3 {
  T x, y, z;
};

// det F, expanded along the first row as Eigen's 3x3 determinant is.
template <class T>
MTLED_HOST_DEVICE inline T determinant(const Matrix3<T>& a) {
  const auto& m = a.m;
  return m[0][0] * (m[1][1] * m[2][2] - m[2][1] * m[1][2]) - m[1][0] * (m[0][1] * m[2][2] - m[2][1] * m[0][2]) +
         m[2][0] * (m[0][1] * m[1][2] - m[1][1] * m[0][2]);
}

// A law may be evaluated at F, with J = det F: J > 0, J finite and every entry of F finite (a NaN anywhere makes J
// NaN, an infinite entry makes J infinite or NaN, so testing J covers F). The Material interface requires refusing
// an inverted or collapsed F instead of hiding it with |J| (which would let inverted material pass as valid).
template <class T>
MTLED_HOST_DEVICE inline MaskOf<T> admissible(const Matrix3<T>& F, const T& J) {
  T sum = J;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) sum = sum + T(0.0) * F.m[i][j];  // NaN if any entry is not finite
  return both(gt(J, T(0.0)), both(le(J, T(DBL_MAX)), eq(sum, J)));
}

// Upper triangle of C = F^T F.
template <class T>
MTLED_HOST_DEVICE inline Matrix3<T> right_cauchy_green(const Matrix3<T>& F) {
  Matrix3<T> C;
  for (int i = 0; i < 3; ++i)
    for (int j = i; j < 3; ++j)
      C.m[i][j] = mul_add(F.m[2][i], F.m[2][j], mul_add(F.m[1][i], F.m[1][j], F.m[0][i] * F.m[0][j]));
  return C;
}

// Upper triangle of C^-1 = F^-1 F^-T, with F^-1 = adj(F) / J: no eigen decomposition, no division but 1 / J.
template <class T>
MTLED_HOST_DEVICE inline Matrix3<T> inverse_right_cauchy_green(const Matrix3<T>& F, const T& J) {
  const T inverse_J = T(1.0) / J;
  const auto& f = F.m;
  Matrix3<T> Fi;  // (F^-1)_ij = cofactor_ji / J
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const int r0 = (j + 1) % 3, r1 = (j + 2) % 3, c0 = (i + 1) % 3, c1 = (i + 2) % 3;
      Fi.m[i][j] = (f[r0][c0] * f[r1][c1] - f[r0][c1] * f[r1][c0]) * inverse_J;
    }
  Matrix3<T> C_inverse;
  for (int i = 0; i < 3; ++i)
    for (int j = i; j < 3; ++j)
      C_inverse.m[i][j] = mul_add(Fi.m[i][2], Fi.m[j][2], mul_add(Fi.m[i][1], Fi.m[j][1], Fi.m[i][0] * Fi.m[j][0]));
  return C_inverse;
}

template <class T>
MTLED_HOST_DEVICE inline Vector3<T> cross(const Vector3<T>& a, const Vector3<T>& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <class T>
MTLED_HOST_DEVICE inline T dot(const Vector3<T>& a, const Vector3<T>& b) {
  return mul_add(a.z, b.z, mul_add(a.y, b.y, a.x * b.x));
}
template <class T>
MTLED_HOST_DEVICE inline Vector3<T> scale(const Vector3<T>& a, const T& s) {
  return {a.x * s, a.y * s, a.z * s};
}
template <class T>
MTLED_HOST_DEVICE inline Vector3<T> select(const MaskOf<T>& m, const Vector3<T>& a, const Vector3<T>& b) {
  return {select(m, a.x, b.x), select(m, a.y, b.y), select(m, a.z, b.z)};
}
template <class T>
MTLED_HOST_DEVICE inline const T& component(const Vector3<T>& v, int i) {
  return i == 0 ? v.x : (i == 1 ? v.y : v.z);
}
// B v for a symmetric B given by its upper triangle.
template <class T>
MTLED_HOST_DEVICE inline Vector3<T> symmetric_times(const Matrix3<T>& B, const Vector3<T>& v) {
  const auto& m = B.m;
  return {mul_add(m[0][2], v.z, mul_add(m[0][1], v.y, m[0][0] * v.x)),
          mul_add(m[1][2], v.z, mul_add(m[1][1], v.y, m[0][1] * v.x)),
          mul_add(m[2][2], v.z, mul_add(m[1][2], v.y, m[0][2] * v.x))};
}

// ---- the eigen decomposition of a symmetric 3x3 matrix ----------------------------------------------------------
// Closed form and accurate when eigenvalues are equal or nearly equal, for laws of the principal stretches (Ogden).
// Eigen's computeDirect() takes every eigenvalue from the trigonometric solution of the characteristic cubic, which
// is ill-conditioned at a double root: with two stretches within 1e-6 (uniaxial load, F near I) the Ogden stress
// came out wrong by ~1e-7 of the P-wave modulus, against ~1e-14 here; Eigen's iterative solver is accurate but
// costs about twice as much. The scheme of Scherzinger & Dohrmann, CMAME 197 (2008) 4007 (also D. Eberly, "A
// Robust Eigensolver for 3x3 Symmetric Matrices", Geometric Tools, 2014):
//  1. shift by the mean eigenvalue and scale, B = (A - m I) / s with max |B_ij| = 1;
//  2. take from the cubic only the eigenvalue farthest from the other two: there the cubic is well conditioned;
//  3. its eigenvector from the best-conditioned cross product of two rows of B - eta I;
//  4. the other two by one Jacobi rotation in the plane orthogonal to it (exact and backward stable for 2x2), so a
//     close pair is resolved to round-off.
// Backward stable: |A - V diag(w) V^T| ~ eps |A| and V orthonormal to ~eps, whatever the spacing of the eigenvalues.

// Where a vector holds 8 doubles (AVX-512) the solver is inlined into the law (a call costs 3% of an Ogden point);
// with narrower vectors GCC's own choice, a call, measured faster (AVX2: 35.6 against 41 ns per Ogden point): the
// inlined whole spills more of its 16 registers.
#undef MTLED_LAW_EIGEN_INLINE
#if defined(MTLED_LAW_SIMD) && HWY_MAX_BYTES >= 64
#define MTLED_LAW_EIGEN_INLINE HWY_INLINE
#else
#define MTLED_LAW_EIGEN_INLINE inline
#endif

template <class T>
struct SymmetricEigen3 {
  T values[3];            // in no particular order
  Vector3<T> vectors[3];  // orthonormal, vectors[i] belongs to values[i]
};

// Reads the upper triangle of A.
template <class T>
MTLED_HOST_DEVICE MTLED_LAW_EIGEN_INLINE SymmetricEigen3<T> symmetric_eigen3(const Matrix3<T>& A) {
  const T zero(0.0), one(1.0);
  const T mean = (A.m[0][0] + A.m[1][1] + A.m[2][2]) * T(1.0 / 3.0);
  Matrix3<T> B = A;
  for (int i = 0; i < 3; ++i) B.m[i][i] = A.m[i][i] - mean;
  T largest = zero;
  for (int i = 0; i < 3; ++i)
    for (int j = i; j < 3; ++j) largest = max(largest, abs(B.m[i][j]));
  // A multiple of the identity (F = I, a pure dilation): every basis is an eigenbasis. Such a point runs on a
  // stand-in, diag(1, 0, -1), and gets the identity and the mean at the end.
  const MaskOf<T> multiple_of_identity = negate(gt(largest, zero));
  // One division and six products rather than six divisions (the divider is a SIMD batch's narrowest unit). A
  // subnormal scale (F = I plus round-off noise) is first raised by 2^54, exactly, so that its inverse is finite;
  // elsewhere that factor is 1 and changes nothing.
  const T rescue = select(lt(largest, T(DBL_MIN)), T(0x1p54), one);
  const T inverse_scale = one / select(multiple_of_identity, one, largest * rescue);
  for (int i = 0; i < 3; ++i)
    for (int j = i; j < 3; ++j) {
      const T stand_in(i != j ? 0.0 : (i == 0 ? 1.0 : (i == 1 ? 0.0 : -1.0)));
      B.m[i][j] = select(multiple_of_identity, stand_in, (B.m[i][j] * rescue) * inverse_scale);
    }
  // Invariants of the (nearly) traceless B: eigenvalues rho cos(theta + 2 pi k / 3) with rho = 2 sqrt(j2 / 3) and
  // cos(3 theta) = 4 det(B) / rho^3. After scaling j2 >= 3/4, so rho >= 1.
  const auto& b = B.m;
  const T j2 = T(0.5) * mul_add(b[2][2], b[2][2], mul_add(b[1][1], b[1][1], b[0][0] * b[0][0])) +
               mul_add(b[1][2], b[1][2], mul_add(b[0][2], b[0][2], b[0][1] * b[0][1]));
  const T rho = T(2.0) * sqrt(j2 * T(1.0 / 3.0));
  Matrix3<T> full = B;
  full.m[1][0] = b[0][1], full.m[2][0] = b[0][2], full.m[2][1] = b[1][2];
  const T cos_3theta = min(one, max(-one, (T(4.0) * determinant(full)) / (rho * (rho * rho))));
  const T theta = acos(cos_3theta) * T(1.0 / 3.0);  // in [0, pi/3]
  // theta < pi/6: the largest eigenvalue is the isolated one (a close pair sits at theta -> 0); otherwise the
  // smallest is (a close pair at theta -> pi/3).
  const T angle = select(lt(theta, T(law_constants::kPi / 6.0)), theta, theta + T(2.0 * law_constants::kPi / 3.0));
  const T eta = rho * cos(angle);

  const Vector3<T> r0{b[0][0] - eta, b[0][1], b[0][2]};
  const Vector3<T> r1{b[0][1], b[1][1] - eta, b[1][2]};
  const Vector3<T> r2{b[0][2], b[1][2], b[2][2] - eta};
  const Vector3<T> c01 = cross(r0, r1), c02 = cross(r0, r2), c12 = cross(r1, r2);
  const T n01 = dot(c01, c01), n02 = dot(c02, c02), n12 = dot(c12, c12);
  const MaskOf<T> take01 = both(ge(n01, n02), ge(n01, n12));
  const MaskOf<T> take02 = and_not(take01, ge(n02, n12));
  const Vector3<T> chosen = select(take01, c01, select(take02, c02, c12));
  const T chosen_norm = select(take01, n01, select(take02, n02, n12));
  const Vector3<T> v1 = scale(chosen, one / sqrt(chosen_norm));

  // (u, w): an orthonormal basis of the plane normal to v1, from v1's two largest components.
  const MaskOf<T> x_larger = gt(abs(v1.x), abs(v1.y));
  Vector3<T> u = select(x_larger, Vector3<T>{-v1.z, zero, v1.x}, Vector3<T>{zero, v1.z, -v1.y});
  u = scale(u, one / sqrt(dot(u, u)));
  const Vector3<T> w = cross(v1, u);
  const T b_uu = dot(u, symmetric_times(B, u)), b_ww = dot(w, symmetric_times(B, w));
  const T b_uw = dot(u, symmetric_times(B, w));
  // Jacobi rotation zeroing b_uw, the smaller of the two angles (Golub & Van Loan, sec. 8.5); t = 0 (no rotation)
  // where b_uw is already 0.
  const MaskOf<T> rotate = ne(b_uw, zero);
  const T tau = (b_ww - b_uu) / (T(2.0) * select(rotate, b_uw, one));
  const T t = zero_unless(rotate, copy_sign(one, tau) / (abs(tau) + sqrt(mul_add(tau, tau, one))));
  const T c = one / sqrt(mul_add(t, t, one)), s = t * c;

  SymmetricEigen3<T> result;
  // The Rayleigh quotient of v1: more accurate than eta from the cubic (second order in v1's error).
  const T eta1 = dot(v1, symmetric_times(B, v1));
  const T eta2 = neg_mul_add(t, b_uw, b_uu), eta3 = mul_add(t, b_uw, b_ww);
  const T etas[3] = {eta1, eta2, eta3};
  for (int k = 0; k < 3; ++k) result.values[k] = select(multiple_of_identity, mean, mul_add(etas[k], largest, mean));
  const Vector3<T> v2{neg_mul_add(s, w.x, c * u.x), neg_mul_add(s, w.y, c * u.y), neg_mul_add(s, w.z, c * u.z)};
  const Vector3<T> v3{mul_add(c, w.x, s * u.x), mul_add(c, w.y, s * u.y), mul_add(c, w.z, s * u.z)};
  result.vectors[0] = select(multiple_of_identity, Vector3<T>{one, zero, zero}, v1);
  result.vectors[1] = select(multiple_of_identity, Vector3<T>{zero, one, zero}, v2);
  result.vectors[2] = select(multiple_of_identity, Vector3<T>{zero, zero, one}, v3);
  return result;
}

// Q diag(s) Q^T, upper triangle (Q's columns are the eigenvectors): a law of the principal stretches' S from its
// principal values.
template <class T>
MTLED_HOST_DEVICE inline Matrix3<T> spectral_sum(const SymmetricEigen3<T>& e, const T (&s)[3]) {
  Matrix3<T> out;
  for (int i = 0; i < 3; ++i)
    for (int j = i; j < 3; ++j) {
      T sum = (component(e.vectors[0], i) * s[0]) * component(e.vectors[0], j);
      sum = mul_add(component(e.vectors[1], i) * s[1], component(e.vectors[1], j), sum);
      out.m[i][j] = mul_add(component(e.vectors[2], i) * s[2], component(e.vectors[2], j), sum);
    }
  return out;
}

// ---- evaluating a law --------------------------------------------------------------------------------------------
// A law is a struct of its constants (Law, defined once) and, between MTLED_LAW_BEGIN and MTLED_LAW_END of its
// own per-target header, two MTLED_HOST_DEVICE function templates:
//   template <class T> Matrix3<T> stress(const Law&, const Matrix3<T>& F, const T& J);  // S, upper triangle
//   template <class T> T energy(const Law&, const Matrix3<T>& F, const T& J);           // W (only T = double)
// They are called with J = det F > 0 where F is admissible; elsewhere (a refused SIMD lane) with J = 1, and the
// result is discarded.

template <class T>
struct LawStress {
  Matrix3<T> S;          // upper triangle; zero where refused
  MaskOf<T> admissible;  // false where F is inadmissible or S not finite (an F so extreme that S overflows)
};

template <class Law, class T>
MTLED_HOST_DEVICE inline LawStress<T> evaluate_stress(const Law& law, const Matrix3<T>& F) {
  const T J = determinant(F);
  LawStress<T> out;
  out.admissible = admissible(F, J);
  if constexpr (std::is_same_v<T, double>) {
    if (!out.admissible) {
      for (auto& row : out.S.m)
        for (double& s : row) s = 0.0;
      return out;
    }
  }
  out.S = stress(law, F, select(out.admissible, J, T(1.0)));
  for (int i = 0; i < 3; ++i)
    for (int j = i; j < 3; ++j) out.admissible = both(out.admissible, eq(out.S.m[i][j] - out.S.m[i][j], T(0.0)));
  for (int i = 0; i < 3; ++i)
    for (int j = i; j < 3; ++j) out.S.m[i][j] = zero_unless(out.admissible, out.S.m[i][j]);
  return out;
}

#ifndef MTLED_LAW_SIMD
// W at F, NaN where F is inadmissible.
template <class Law>
MTLED_HOST_DEVICE inline double evaluate_energy(const Law& law, const Matrix3<double>& F) {
  const double J = determinant(F);
  if (!admissible(F, J)) return NAN;
  return energy(law, F, J);
}
#endif

MTLED_LAW_END
#endif  // MTLED_LAW_ARITHMETIC_INL_H_
