// Vectorised building blocks of the hyperelastic laws, for their stress_batch(): one SIMD lane per
// integration point, the same arithmetic as the one-point code in hyperelastic.hpp and symmetric_eigen3.hpp
// (which stay the reference), with branches turned into selects. Written once with Google Highway and
// compiled for every instruction set it targets; the plugin picks the best one the CPU has at run time.
//
// Per-target include guard (Highway's convention): this header is included once per target by
// hwy/foreach_target.h.
#if defined(MTLED_HYPERELASTIC_SIMD_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef MTLED_HYPERELASTIC_SIMD_INL_H_
#undef MTLED_HYPERELASTIC_SIMD_INL_H_
#else
#define MTLED_HYPERELASTIC_SIMD_INL_H_
#endif

#include <hwy/contrib/math/math-inl.h>
#include <hwy/highway.h>

#include <numbers>

#include "mtled/interfaces/material.hpp"

HWY_BEFORE_NAMESPACE();
namespace mtled::HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using DoubleTag = hn::ScalableTag<double>;
using DoubleVec = hn::Vec<DoubleTag>;
using DoubleMask = hn::Mask<DoubleTag>;

// A 3x3 matrix, one lane per point.
struct Mat3V {
  DoubleVec m[3][3];
};
struct Vec3V {
  DoubleVec x, y, z;
};

inline Mat3V load_matrix(DoubleTag d, const double (&batch)[9][StressBatch::kCapacity], int p) {
  Mat3V a;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) a.m[i][j] = hn::Load(d, &batch[3 * i + j][p]);
  return a;
}

inline void store_symmetric(DoubleTag d, const Mat3V& s, double (&batch)[9][StressBatch::kCapacity], int p) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) hn::Store(i <= j ? s.m[i][j] : s.m[j][i], d, &batch[3 * i + j][p]);
}

inline void store_admissible(DoubleTag d, DoubleMask admissible, bool (&batch)[StressBatch::kCapacity], int p) {
  alignas(64) double lanes[StressBatch::kCapacity];
  hn::Store(hn::IfThenElseZero(admissible, hn::Set(d, 1.0)), d, lanes);
  for (std::size_t i = 0; i < hn::Lanes(d); ++i) batch[p + static_cast<int>(i)] = lanes[i] != 0.0;
}

// Zero in the refused lanes, so that a batch never carries a stress for them.
inline Mat3V zero_unless(DoubleMask admissible, const Mat3V& a) {
  Mat3V out;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) out.m[i][j] = hn::IfThenElseZero(admissible, a.m[i][j]);
  return out;
}

// The law's result for lanes p ..: lanes whose stress is not finite (an F so extreme that S overflows, or C has
// a round-off eigenvalue <= 0) are refused too; refused lanes carry S = 0.
inline void store_stress(DoubleTag d, const Mat3V& S, DoubleMask admissible, StressBatch& batch, int p) {
  for (int i = 0; i < 3; ++i)
    for (int j = i; j < 3; ++j)
      admissible = hn::And(admissible, hn::Eq(hn::Sub(S.m[i][j], S.m[i][j]), hn::Zero(d)));
  store_symmetric(d, zero_unless(admissible, S), batch.S, p);
  store_admissible(d, admissible, batch.admissible, p);
}

// det F, expanded along the first row as Eigen's 3x3 determinant is.
inline DoubleVec determinant(const Mat3V& a) {
  const auto& m = a.m;
  return hn::Add(hn::Sub(hn::Mul(m[0][0], hn::Sub(hn::Mul(m[1][1], m[2][2]), hn::Mul(m[2][1], m[1][2]))),
                         hn::Mul(m[1][0], hn::Sub(hn::Mul(m[0][1], m[2][2]), hn::Mul(m[2][1], m[0][2])))),
                 hn::Mul(m[2][0], hn::Sub(hn::Mul(m[0][1], m[1][2]), hn::Mul(m[1][1], m[0][2]))));
}

// hyperelastic::admissible: J > 0, J finite and every entry of F finite (a NaN anywhere makes J NaN, an
// infinite entry makes J infinite or NaN, so testing J covers F).
inline DoubleMask admissible(DoubleTag d, const Mat3V& F, DoubleVec J) {
  DoubleVec sum = J;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) sum = hn::Add(sum, hn::Mul(hn::Zero(d), F.m[i][j]));  // NaN if any entry is not finite
  const DoubleVec huge = hn::Set(d, std::numeric_limits<double>::max());
  return hn::And(hn::Gt(J, hn::Zero(d)), hn::And(hn::Le(J, huge), hn::Eq(sum, J)));
}

// Upper triangle of C = F^T F.
inline Mat3V right_cauchy_green(const Mat3V& F) {
  Mat3V C;
  for (int i = 0; i < 3; ++i)
    for (int j = i; j < 3; ++j)
      C.m[i][j] = hn::MulAdd(F.m[2][i], F.m[2][j], hn::MulAdd(F.m[1][i], F.m[1][j], hn::Mul(F.m[0][i], F.m[0][j])));
  return C;
}

inline DoubleVec power(DoubleTag d, DoubleVec x, double exponent) {  // x > 0
  return hn::Exp(d, hn::Mul(hn::Set(d, exponent), hn::Log(d, x)));
}

inline Vec3V cross(const Vec3V& a, const Vec3V& b) {
  return {hn::Sub(hn::Mul(a.y, b.z), hn::Mul(a.z, b.y)), hn::Sub(hn::Mul(a.z, b.x), hn::Mul(a.x, b.z)),
          hn::Sub(hn::Mul(a.x, b.y), hn::Mul(a.y, b.x))};
}
inline DoubleVec dot(const Vec3V& a, const Vec3V& b) {
  return hn::MulAdd(a.z, b.z, hn::MulAdd(a.y, b.y, hn::Mul(a.x, b.x)));
}
inline Vec3V scale(const Vec3V& a, DoubleVec s) { return {hn::Mul(a.x, s), hn::Mul(a.y, s), hn::Mul(a.z, s)}; }
inline Vec3V select(DoubleMask m, const Vec3V& a, const Vec3V& b) {
  return {hn::IfThenElse(m, a.x, b.x), hn::IfThenElse(m, a.y, b.y), hn::IfThenElse(m, a.z, b.z)};
}
// B v for a symmetric B given by its upper triangle.
inline Vec3V symmetric_times(const Mat3V& B, const Vec3V& v) {
  const auto& m = B.m;
  return {hn::MulAdd(m[0][2], v.z, hn::MulAdd(m[0][1], v.y, hn::Mul(m[0][0], v.x))),
          hn::MulAdd(m[1][2], v.z, hn::MulAdd(m[1][1], v.y, hn::Mul(m[0][1], v.x))),
          hn::MulAdd(m[2][2], v.z, hn::MulAdd(m[1][2], v.y, hn::Mul(m[0][2], v.x)))};
}

struct SymmetricEigen3V {
  DoubleVec values[3];
  Vec3V vectors[3];
};

// symmetric_eigen3() lane by lane (the scheme of Scherzinger & Dohrmann, CMAME 197 (2008) 4007, described in
// symmetric_eigen3.hpp): the eigenvalue farthest from the other two from the characteristic cubic, its vector
// from the best-conditioned cross product, the other two by one Jacobi rotation in the orthogonal plane.
// Reads the upper triangle of A.
inline SymmetricEigen3V symmetric_eigen3(DoubleTag d, const Mat3V& A) {
  const DoubleVec zero = hn::Zero(d), one = hn::Set(d, 1.0);
  const DoubleVec mean = hn::Mul(hn::Add(hn::Add(A.m[0][0], A.m[1][1]), A.m[2][2]), hn::Set(d, 1.0 / 3.0));
  Mat3V B = A;
  for (int i = 0; i < 3; ++i) B.m[i][i] = hn::Sub(A.m[i][i], mean);
  DoubleVec largest = zero;
  for (int i = 0; i < 3; ++i)
    for (int j = i; j < 3; ++j) largest = hn::Max(largest, hn::Abs(B.m[i][j]));
  // A multiple of the identity: any basis is an eigenbasis. Such lanes run on a stand-in, diag(1, 0, -1), and
  // get the identity and the mean at the end.
  const DoubleMask multiple_of_identity = hn::Not(hn::Gt(largest, zero));
  // One division and six products rather than six divisions (the divider is the batch's narrowest unit).
  const DoubleVec inverse_scale = hn::Div(one, hn::IfThenElse(multiple_of_identity, one, largest));
  for (int i = 0; i < 3; ++i)
    for (int j = i; j < 3; ++j) {
      const DoubleVec stand_in = hn::Set(d, i != j ? 0.0 : (i == 0 ? 1.0 : (i == 1 ? 0.0 : -1.0)));
      B.m[i][j] = hn::IfThenElse(multiple_of_identity, stand_in, hn::Mul(B.m[i][j], inverse_scale));
    }
  const auto& b = B.m;
  const DoubleVec j2 = hn::Add(
      hn::Mul(hn::Set(d, 0.5), hn::MulAdd(b[2][2], b[2][2], hn::MulAdd(b[1][1], b[1][1], hn::Mul(b[0][0], b[0][0])))),
      hn::MulAdd(b[1][2], b[1][2], hn::MulAdd(b[0][2], b[0][2], hn::Mul(b[0][1], b[0][1]))));
  const DoubleVec rho = hn::Mul(hn::Set(d, 2.0), hn::Sqrt(hn::Mul(j2, hn::Set(d, 1.0 / 3.0))));
  Mat3V full = B;
  full.m[1][0] = b[0][1], full.m[2][0] = b[0][2], full.m[2][1] = b[1][2];
  const DoubleVec cos_3theta = hn::Min(
      one, hn::Max(hn::Neg(one), hn::Div(hn::Mul(hn::Set(d, 4.0), determinant(full)), hn::Mul(rho, hn::Mul(rho, rho)))));
  const DoubleVec theta = hn::Mul(hn::Acos(d, cos_3theta), hn::Set(d, 1.0 / 3.0));
  const DoubleVec angle = hn::IfThenElse(hn::Lt(theta, hn::Set(d, std::numbers::pi / 6.0)), theta,
                                         hn::Add(theta, hn::Set(d, 2.0 * std::numbers::pi / 3.0)));
  const DoubleVec eta = hn::Mul(rho, hn::Cos(d, angle));

  const Vec3V r0{hn::Sub(b[0][0], eta), b[0][1], b[0][2]};
  const Vec3V r1{b[0][1], hn::Sub(b[1][1], eta), b[1][2]};
  const Vec3V r2{b[0][2], b[1][2], hn::Sub(b[2][2], eta)};
  const Vec3V c01 = cross(r0, r1), c02 = cross(r0, r2), c12 = cross(r1, r2);
  const DoubleVec n01 = dot(c01, c01), n02 = dot(c02, c02), n12 = dot(c12, c12);
  const DoubleMask take01 = hn::And(hn::Ge(n01, n02), hn::Ge(n01, n12));
  const DoubleMask take02 = hn::AndNot(take01, hn::Ge(n02, n12));
  const Vec3V chosen = select(take01, c01, select(take02, c02, c12));
  const DoubleVec chosen_norm = hn::IfThenElse(take01, n01, hn::IfThenElse(take02, n02, n12));
  const Vec3V v1 = scale(chosen, hn::Div(one, hn::Sqrt(chosen_norm)));

  // (u, w): an orthonormal basis of the plane normal to v1, from v1's two largest components.
  const DoubleMask x_larger = hn::Gt(hn::Abs(v1.x), hn::Abs(v1.y));
  Vec3V u = select(x_larger, Vec3V{hn::Neg(v1.z), zero, v1.x}, Vec3V{zero, v1.z, hn::Neg(v1.y)});
  u = scale(u, hn::Div(one, hn::Sqrt(dot(u, u))));
  const Vec3V w = cross(v1, u);
  const DoubleVec b_uu = dot(u, symmetric_times(B, u)), b_ww = dot(w, symmetric_times(B, w));
  const DoubleVec b_uw = dot(u, symmetric_times(B, w));
  // Jacobi rotation zeroing b_uw, the smaller of the two angles (Golub & Van Loan, sec. 8.5); t = 0 (no rotation)
  // where b_uw is already 0.
  const DoubleMask rotate = hn::Ne(b_uw, zero);
  const DoubleVec tau = hn::Div(hn::Sub(b_ww, b_uu), hn::Mul(hn::Set(d, 2.0), hn::IfThenElse(rotate, b_uw, one)));
  const DoubleVec t = hn::IfThenElseZero(
      rotate, hn::Div(hn::CopySign(one, tau), hn::Add(hn::Abs(tau), hn::Sqrt(hn::MulAdd(tau, tau, one)))));
  const DoubleVec c = hn::Div(one, hn::Sqrt(hn::MulAdd(t, t, one))), s = hn::Mul(t, c);

  SymmetricEigen3V result;
  // The Rayleigh quotient of v1: more accurate than eta from the cubic (second order in v1's error).
  const DoubleVec eta1 = dot(v1, symmetric_times(B, v1));
  const DoubleVec eta2 = hn::NegMulAdd(t, b_uw, b_uu), eta3 = hn::MulAdd(t, b_uw, b_ww);
  const DoubleVec etas[3] = {eta1, eta2, eta3};
  for (int k = 0; k < 3; ++k) result.values[k] = hn::IfThenElse(multiple_of_identity, mean, hn::MulAdd(etas[k], largest, mean));
  const Vec3V v2{hn::NegMulAdd(s, w.x, hn::Mul(c, u.x)), hn::NegMulAdd(s, w.y, hn::Mul(c, u.y)),
                 hn::NegMulAdd(s, w.z, hn::Mul(c, u.z))};
  const Vec3V v3{hn::MulAdd(c, w.x, hn::Mul(s, u.x)), hn::MulAdd(c, w.y, hn::Mul(s, u.y)),
                 hn::MulAdd(c, w.z, hn::Mul(s, u.z))};
  result.vectors[0] = select(multiple_of_identity, Vec3V{one, zero, zero}, v1);
  result.vectors[1] = select(multiple_of_identity, Vec3V{zero, one, zero}, v2);
  result.vectors[2] = select(multiple_of_identity, Vec3V{zero, zero, one}, v3);
  return result;
}

// Q diag(s) Q^T, upper triangle (Q's columns are the vectors).
inline Mat3V spectral_sum(const SymmetricEigen3V& e, const DoubleVec (&s)[3]) {
  Mat3V out;
  auto component = [&](const Vec3V& v, int i) { return i == 0 ? v.x : (i == 1 ? v.y : v.z); };
  for (int i = 0; i < 3; ++i)
    for (int j = i; j < 3; ++j) {
      DoubleVec sum = hn::Mul(hn::Mul(component(e.vectors[0], i), s[0]), component(e.vectors[0], j));
      sum = hn::MulAdd(hn::Mul(component(e.vectors[1], i), s[1]), component(e.vectors[1], j), sum);
      out.m[i][j] = hn::MulAdd(hn::Mul(component(e.vectors[2], i), s[2]), component(e.vectors[2], j), sum);
    }
  return out;
}

}  // namespace mtled::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#endif  // MTLED_HYPERELASTIC_SIMD_INL_H_
