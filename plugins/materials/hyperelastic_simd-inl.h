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

#include <cstddef>
#include <numbers>

#include "mtled/interfaces/material.hpp"

HWY_BEFORE_NAMESPACE();
namespace mtled::HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using DoubleTag = hn::ScalableTag<double>;
using DoubleVec = hn::Vec<DoubleTag>;
using DoubleMask = hn::Mask<DoubleTag>;

// One pass of a law over a batch works on kParts hardware vectors side by side, each operation applied to every
// part in turn. The Ogden stress is one long chain of dependent operations per lane (the eigen solver's divisions
// and roots, acos, cos, logs, exponentials): where a vector holds fewer than 8 doubles (AVX2, SSE4), two parts put
// two independent chains next to each other in the instruction stream, so that the CPU overlaps them instead of
// running a batch's halves one after the other. With 8 doubles a vector (AVX-512) one part is the plain code.
inline constexpr int kParts = hn::MaxLanes(DoubleTag()) >= 8 ? 1 : 2;
inline constexpr int kPassLanes = kParts * static_cast<int>(hn::MaxLanes(DoubleTag()));
static_assert(StressBatch::kCapacity % kPassLanes == 0, "a batch is a whole number of passes");

struct PointVec {  // one lane per integration point
  DoubleVec part[kParts];
};
struct PointMask {
  DoubleMask part[kParts];
};

// op applied to every part: each<PointVec>(op, a, b) is op(a.part[k], b.part[k]) for k = 0, 1, ...
template <class Result, class Op, class... Packs>
inline Result each(Op op, const Packs&... packs) {
  Result r;
  for (int k = 0; k < kParts; ++k) r.part[k] = op(packs.part[k]...);
  return r;
}

inline PointVec set(double value) {
  PointVec r;
  for (int k = 0; k < kParts; ++k) r.part[k] = hn::Set(DoubleTag(), value);
  return r;
}
inline PointVec zeros() { return set(0.0); }
inline PointVec add(const PointVec& a, const PointVec& b) {
  return each<PointVec>([](auto x, auto y) { return hn::Add(x, y); }, a, b);
}
inline PointVec sub(const PointVec& a, const PointVec& b) {
  return each<PointVec>([](auto x, auto y) { return hn::Sub(x, y); }, a, b);
}
inline PointVec mul(const PointVec& a, const PointVec& b) {
  return each<PointVec>([](auto x, auto y) { return hn::Mul(x, y); }, a, b);
}
inline PointVec div(const PointVec& a, const PointVec& b) {
  return each<PointVec>([](auto x, auto y) { return hn::Div(x, y); }, a, b);
}
inline PointVec min(const PointVec& a, const PointVec& b) {
  return each<PointVec>([](auto x, auto y) { return hn::Min(x, y); }, a, b);
}
inline PointVec max(const PointVec& a, const PointVec& b) {
  return each<PointVec>([](auto x, auto y) { return hn::Max(x, y); }, a, b);
}
inline PointVec copy_sign(const PointVec& a, const PointVec& b) {
  return each<PointVec>([](auto x, auto y) { return hn::CopySign(x, y); }, a, b);
}
inline PointVec mul_add(const PointVec& a, const PointVec& b, const PointVec& c) {  // a b + c
  return each<PointVec>([](auto x, auto y, auto z) { return hn::MulAdd(x, y, z); }, a, b, c);
}
inline PointVec neg_mul_add(const PointVec& a, const PointVec& b, const PointVec& c) {  // c - a b
  return each<PointVec>([](auto x, auto y, auto z) { return hn::NegMulAdd(x, y, z); }, a, b, c);
}
inline PointVec neg(const PointVec& a) {
  return each<PointVec>([](auto x) { return hn::Neg(x); }, a);
}
inline PointVec abs(const PointVec& a) {
  return each<PointVec>([](auto x) { return hn::Abs(x); }, a);
}
inline PointVec sqrt(const PointVec& a) {
  return each<PointVec>([](auto x) { return hn::Sqrt(x); }, a);
}
inline PointVec exp(const PointVec& a) {
  return each<PointVec>([](auto x) { return hn::Exp(DoubleTag(), x); }, a);
}
inline PointVec log(const PointVec& a) {
  return each<PointVec>([](auto x) { return hn::Log(DoubleTag(), x); }, a);
}
inline PointVec acos(const PointVec& a) {
  return each<PointVec>([](auto x) { return hn::Acos(DoubleTag(), x); }, a);
}
inline PointVec cos(const PointVec& a) {
  return each<PointVec>([](auto x) { return hn::Cos(DoubleTag(), x); }, a);
}

inline PointMask eq(const PointVec& a, const PointVec& b) {
  return each<PointMask>([](auto x, auto y) { return hn::Eq(x, y); }, a, b);
}
inline PointMask ne(const PointVec& a, const PointVec& b) {
  return each<PointMask>([](auto x, auto y) { return hn::Ne(x, y); }, a, b);
}
inline PointMask lt(const PointVec& a, const PointVec& b) {
  return each<PointMask>([](auto x, auto y) { return hn::Lt(x, y); }, a, b);
}
inline PointMask le(const PointVec& a, const PointVec& b) {
  return each<PointMask>([](auto x, auto y) { return hn::Le(x, y); }, a, b);
}
inline PointMask gt(const PointVec& a, const PointVec& b) {
  return each<PointMask>([](auto x, auto y) { return hn::Gt(x, y); }, a, b);
}
inline PointMask ge(const PointVec& a, const PointVec& b) {
  return each<PointMask>([](auto x, auto y) { return hn::Ge(x, y); }, a, b);
}
inline PointMask both(const PointMask& a, const PointMask& b) {
  return each<PointMask>([](auto x, auto y) { return hn::And(x, y); }, a, b);
}
inline PointMask and_not(const PointMask& a, const PointMask& b) {  // (not a) and b, as hn::AndNot
  return each<PointMask>([](auto x, auto y) { return hn::AndNot(x, y); }, a, b);
}
inline PointMask negate(const PointMask& a) {
  return each<PointMask>([](auto x) { return hn::Not(x); }, a);
}
inline PointVec select(const PointMask& m, const PointVec& a, const PointVec& b) {
  return each<PointVec>([](auto mask, auto x, auto y) { return hn::IfThenElse(mask, x, y); }, m, a, b);
}
inline PointVec zero_unless(const PointMask& m, const PointVec& a) {
  return each<PointVec>([](auto mask, auto x) { return hn::IfThenElseZero(mask, x); }, m, a);
}

// A 3x3 matrix, one lane per point.
struct Mat3V {
  PointVec m[3][3];
};
struct Vec3V {
  PointVec x, y, z;
};

inline PointVec load(const double (&values)[StressBatch::kCapacity], int p) {
  PointVec r;
  const DoubleTag d;
  for (int k = 0; k < kParts; ++k) r.part[k] = hn::Load(d, &values[p + k * static_cast<int>(hn::Lanes(d))]);
  return r;
}
inline void store(const PointVec& v, double (&values)[StressBatch::kCapacity], int p) {
  const DoubleTag d;
  for (int k = 0; k < kParts; ++k) hn::Store(v.part[k], d, &values[p + k * static_cast<int>(hn::Lanes(d))]);
}

inline Mat3V load_matrix(const double (&batch)[9][StressBatch::kCapacity], int p) {
  Mat3V a;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) a.m[i][j] = load(batch[3 * i + j], p);
  return a;
}

inline void store_symmetric(const Mat3V& s, double (&batch)[9][StressBatch::kCapacity], int p) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) store(i <= j ? s.m[i][j] : s.m[j][i], batch[3 * i + j], p);
}

inline void store_admissible(const PointMask& admissible, bool (&batch)[StressBatch::kCapacity], int p) {
  alignas(64) double lanes[StressBatch::kCapacity];
  store(zero_unless(admissible, set(1.0)), lanes, 0);
  for (int i = 0; i < kPassLanes; ++i) batch[p + i] = lanes[i] != 0.0;
}

// Zero in the refused lanes, so that a batch never carries a stress for them.
inline Mat3V zero_unless(const PointMask& admissible, const Mat3V& a) {
  Mat3V out;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) out.m[i][j] = zero_unless(admissible, a.m[i][j]);
  return out;
}

// The law's result for lanes p ..: lanes whose stress is not finite (an F so extreme that S overflows, or C has
// a round-off eigenvalue <= 0) are refused too; refused lanes carry S = 0.
inline void store_stress(const Mat3V& S, PointMask admissible, StressBatch& batch, int p) {
  for (int i = 0; i < 3; ++i)
    for (int j = i; j < 3; ++j) admissible = both(admissible, eq(sub(S.m[i][j], S.m[i][j]), zeros()));
  store_symmetric(zero_unless(admissible, S), batch.S, p);
  store_admissible(admissible, batch.admissible, p);
}

// det F, expanded along the first row as Eigen's 3x3 determinant is.
inline PointVec determinant(const Mat3V& a) {
  const auto& m = a.m;
  return add(sub(mul(m[0][0], sub(mul(m[1][1], m[2][2]), mul(m[2][1], m[1][2]))),
                 mul(m[1][0], sub(mul(m[0][1], m[2][2]), mul(m[2][1], m[0][2])))),
             mul(m[2][0], sub(mul(m[0][1], m[1][2]), mul(m[1][1], m[0][2]))));
}

// hyperelastic::admissible: J > 0, J finite and every entry of F finite (a NaN anywhere makes J NaN, an
// infinite entry makes J infinite or NaN, so testing J covers F).
inline PointMask admissible(const Mat3V& F, const PointVec& J) {
  PointVec sum = J;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) sum = add(sum, mul(zeros(), F.m[i][j]));  // NaN if any entry is not finite
  const PointVec huge = set(std::numeric_limits<double>::max());
  return both(gt(J, zeros()), both(le(J, huge), eq(sum, J)));
}

// Upper triangle of C = F^T F.
inline Mat3V right_cauchy_green(const Mat3V& F) {
  Mat3V C;
  for (int i = 0; i < 3; ++i)
    for (int j = i; j < 3; ++j)
      C.m[i][j] = mul_add(F.m[2][i], F.m[2][j], mul_add(F.m[1][i], F.m[1][j], mul(F.m[0][i], F.m[0][j])));
  return C;
}

inline Vec3V cross(const Vec3V& a, const Vec3V& b) {
  return {sub(mul(a.y, b.z), mul(a.z, b.y)), sub(mul(a.z, b.x), mul(a.x, b.z)), sub(mul(a.x, b.y), mul(a.y, b.x))};
}
inline PointVec dot(const Vec3V& a, const Vec3V& b) { return mul_add(a.z, b.z, mul_add(a.y, b.y, mul(a.x, b.x))); }
inline Vec3V scale(const Vec3V& a, const PointVec& s) { return {mul(a.x, s), mul(a.y, s), mul(a.z, s)}; }
inline Vec3V select(const PointMask& m, const Vec3V& a, const Vec3V& b) {
  return {select(m, a.x, b.x), select(m, a.y, b.y), select(m, a.z, b.z)};
}
// B v for a symmetric B given by its upper triangle.
inline Vec3V symmetric_times(const Mat3V& B, const Vec3V& v) {
  const auto& m = B.m;
  return {mul_add(m[0][2], v.z, mul_add(m[0][1], v.y, mul(m[0][0], v.x))),
          mul_add(m[1][2], v.z, mul_add(m[1][1], v.y, mul(m[0][1], v.x))),
          mul_add(m[2][2], v.z, mul_add(m[1][2], v.y, mul(m[0][2], v.x)))};
}

// Inlined where one part runs, as the code before parts was (a call costs AVX-512 3%); with two parts GCC's own
// choice, a call, measured faster than inlining it (AVX2: 35.6 against 41 ns per Ogden point): the inlined whole
// spills more of its 16 registers.
#undef MTLED_EIGEN_INLINE
#if HWY_MAX_BYTES >= 64
#define MTLED_EIGEN_INLINE HWY_INLINE
#else
#define MTLED_EIGEN_INLINE inline
#endif

struct SymmetricEigen3V {
  PointVec values[3];
  Vec3V vectors[3];
};

// symmetric_eigen3() lane by lane (the scheme of Scherzinger & Dohrmann, CMAME 197 (2008) 4007, described in
// symmetric_eigen3.hpp): the eigenvalue farthest from the other two from the characteristic cubic, its vector
// from the best-conditioned cross product, the other two by one Jacobi rotation in the orthogonal plane.
// Reads the upper triangle of A.
MTLED_EIGEN_INLINE SymmetricEigen3V symmetric_eigen3(const Mat3V& A) {
  const PointVec zero = zeros(), one = set(1.0);
  const PointVec mean = mul(add(add(A.m[0][0], A.m[1][1]), A.m[2][2]), set(1.0 / 3.0));
  Mat3V B = A;
  for (int i = 0; i < 3; ++i) B.m[i][i] = sub(A.m[i][i], mean);
  PointVec largest = zero;
  for (int i = 0; i < 3; ++i)
    for (int j = i; j < 3; ++j) largest = max(largest, abs(B.m[i][j]));
  // A multiple of the identity: any basis is an eigenbasis. Such lanes run on a stand-in, diag(1, 0, -1), and
  // get the identity and the mean at the end.
  const PointMask multiple_of_identity = negate(gt(largest, zero));
  // One division and six products rather than six divisions (the divider is the batch's narrowest unit).
  const PointVec inverse_scale = div(one, select(multiple_of_identity, one, largest));
  for (int i = 0; i < 3; ++i)
    for (int j = i; j < 3; ++j) {
      const PointVec stand_in = set(i != j ? 0.0 : (i == 0 ? 1.0 : (i == 1 ? 0.0 : -1.0)));
      B.m[i][j] = select(multiple_of_identity, stand_in, mul(B.m[i][j], inverse_scale));
    }
  const auto& b = B.m;
  const PointVec j2 = add(mul(set(0.5), mul_add(b[2][2], b[2][2], mul_add(b[1][1], b[1][1], mul(b[0][0], b[0][0])))),
                          mul_add(b[1][2], b[1][2], mul_add(b[0][2], b[0][2], mul(b[0][1], b[0][1]))));
  const PointVec rho = mul(set(2.0), sqrt(mul(j2, set(1.0 / 3.0))));
  Mat3V full = B;
  full.m[1][0] = b[0][1], full.m[2][0] = b[0][2], full.m[2][1] = b[1][2];
  const PointVec cos_3theta = min(one, max(neg(one), div(mul(set(4.0), determinant(full)), mul(rho, mul(rho, rho)))));
  const PointVec theta = mul(acos(cos_3theta), set(1.0 / 3.0));
  const PointVec angle =
      select(lt(theta, set(std::numbers::pi / 6.0)), theta, add(theta, set(2.0 * std::numbers::pi / 3.0)));
  const PointVec eta = mul(rho, cos(angle));

  const Vec3V r0{sub(b[0][0], eta), b[0][1], b[0][2]};
  const Vec3V r1{b[0][1], sub(b[1][1], eta), b[1][2]};
  const Vec3V r2{b[0][2], b[1][2], sub(b[2][2], eta)};
  const Vec3V c01 = cross(r0, r1), c02 = cross(r0, r2), c12 = cross(r1, r2);
  const PointVec n01 = dot(c01, c01), n02 = dot(c02, c02), n12 = dot(c12, c12);
  const PointMask take01 = both(ge(n01, n02), ge(n01, n12));
  const PointMask take02 = and_not(take01, ge(n02, n12));
  const Vec3V chosen = select(take01, c01, select(take02, c02, c12));
  const PointVec chosen_norm = select(take01, n01, select(take02, n02, n12));
  const Vec3V v1 = scale(chosen, div(one, sqrt(chosen_norm)));

  // (u, w): an orthonormal basis of the plane normal to v1, from v1's two largest components.
  const PointMask x_larger = gt(abs(v1.x), abs(v1.y));
  Vec3V u = select(x_larger, Vec3V{neg(v1.z), zero, v1.x}, Vec3V{zero, v1.z, neg(v1.y)});
  u = scale(u, div(one, sqrt(dot(u, u))));
  const Vec3V w = cross(v1, u);
  const PointVec b_uu = dot(u, symmetric_times(B, u)), b_ww = dot(w, symmetric_times(B, w));
  const PointVec b_uw = dot(u, symmetric_times(B, w));
  // Jacobi rotation zeroing b_uw, the smaller of the two angles (Golub & Van Loan, sec. 8.5); t = 0 (no rotation)
  // where b_uw is already 0.
  const PointMask rotate = ne(b_uw, zero);
  const PointVec tau = div(sub(b_ww, b_uu), mul(set(2.0), select(rotate, b_uw, one)));
  const PointVec t = zero_unless(rotate, div(copy_sign(one, tau), add(abs(tau), sqrt(mul_add(tau, tau, one)))));
  const PointVec c = div(one, sqrt(mul_add(t, t, one))), s = mul(t, c);

  SymmetricEigen3V result;
  // The Rayleigh quotient of v1: more accurate than eta from the cubic (second order in v1's error).
  const PointVec eta1 = dot(v1, symmetric_times(B, v1));
  const PointVec eta2 = neg_mul_add(t, b_uw, b_uu), eta3 = mul_add(t, b_uw, b_ww);
  const PointVec etas[3] = {eta1, eta2, eta3};
  for (int k = 0; k < 3; ++k) result.values[k] = select(multiple_of_identity, mean, mul_add(etas[k], largest, mean));
  const Vec3V v2{neg_mul_add(s, w.x, mul(c, u.x)), neg_mul_add(s, w.y, mul(c, u.y)), neg_mul_add(s, w.z, mul(c, u.z))};
  const Vec3V v3{mul_add(c, w.x, mul(s, u.x)), mul_add(c, w.y, mul(s, u.y)), mul_add(c, w.z, mul(s, u.z))};
  result.vectors[0] = select(multiple_of_identity, Vec3V{one, zero, zero}, v1);
  result.vectors[1] = select(multiple_of_identity, Vec3V{zero, one, zero}, v2);
  result.vectors[2] = select(multiple_of_identity, Vec3V{zero, zero, one}, v3);
  return result;
}

// Q diag(s) Q^T, upper triangle (Q's columns are the vectors).
inline Mat3V spectral_sum(const SymmetricEigen3V& e, const PointVec (&s)[3]) {
  Mat3V out;
  auto component = [&](const Vec3V& v, int i) { return i == 0 ? v.x : (i == 1 ? v.y : v.z); };
  for (int i = 0; i < 3; ++i)
    for (int j = i; j < 3; ++j) {
      PointVec sum = mul(mul(component(e.vectors[0], i), s[0]), component(e.vectors[0], j));
      sum = mul_add(mul(component(e.vectors[1], i), s[1]), component(e.vectors[1], j), sum);
      out.m[i][j] = mul_add(mul(component(e.vectors[2], i), s[2]), component(e.vectors[2], j), sum);
    }
  return out;
}

}  // namespace mtled::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#endif  // MTLED_HYPERELASTIC_SIMD_INL_H_
