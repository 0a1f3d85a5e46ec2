// A law's stress_batch() from its single source (arithmetic-inl.h): the law's stress templates instantiated with
// T = PointVec, one SIMD lane per integration point, compiled with Google Highway for every instruction set it
// targets and dispatched at run time to the best one the CPU has. A law's batch file is, for a law `MyLaw` whose
// header is my_law-inl.h:
//
//   #undef HWY_TARGET_INCLUDE
//   #define HWY_TARGET_INCLUDE "my_law_batch.cpp"   // this file
//   #include <hwy/foreach_target.h>  // IWYU pragma: keep
//   #include "mtled/law/stress_batch-inl.h"        // before the law's header
//   #include "my_law-inl.h"
//   MTLED_LAW_STRESS_BATCH(MyLaw, my_law_stress_batch)
//   #if HWY_ONCE
//   MTLED_LAW_STRESS_BATCH_DISPATCH(MyLaw, my_law_stress_batch)
//   #endif
//
// which defines mtled::my_law_stress_batch(const MyLaw&, StressBatch&) for the material's stress_batch().
// Per-target include guard (Highway's convention): this header is included once per target by
// hwy/foreach_target.h.
#if defined(MTLED_LAW_STRESS_BATCH_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef MTLED_LAW_STRESS_BATCH_INL_H_
#undef MTLED_LAW_STRESS_BATCH_INL_H_
#else
#define MTLED_LAW_STRESS_BATCH_INL_H_
#endif

#include <hwy/contrib/math/math-inl.h>
#include <hwy/highway.h>

#include <cstddef>

#include "mtled/interfaces/material.hpp"

#ifndef MTLED_LAW_SIMD
#if defined(MTLED_LAW_ARITHMETIC_ONCE_)
#error "include mtled/law/stress_batch-inl.h before mtled/law/arithmetic-inl.h and any law's header"
#endif
#define MTLED_LAW_SIMD
#endif
#include "mtled/law/arithmetic-inl.h"

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
  PointVec() = default;
  explicit PointVec(double value) {  // every lane `value`: a law's constants, T(value)
    for (int k = 0; k < kParts; ++k) part[k] = hn::Set(DoubleTag(), value);
  }
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

inline PointVec operator+(const PointVec& a, const PointVec& b) {
  return each<PointVec>([](auto x, auto y) { return hn::Add(x, y); }, a, b);
}
inline PointVec operator-(const PointVec& a, const PointVec& b) {
  return each<PointVec>([](auto x, auto y) { return hn::Sub(x, y); }, a, b);
}
inline PointVec operator*(const PointVec& a, const PointVec& b) {
  return each<PointVec>([](auto x, auto y) { return hn::Mul(x, y); }, a, b);
}
inline PointVec operator/(const PointVec& a, const PointVec& b) {
  return each<PointVec>([](auto x, auto y) { return hn::Div(x, y); }, a, b);
}
inline PointVec operator-(const PointVec& a) {
  return each<PointVec>([](auto x) { return hn::Neg(x); }, a);
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

inline Matrix3<PointVec> load_matrix(const double (&batch)[9][StressBatch::kCapacity], int p) {
  Matrix3<PointVec> a;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) a.m[i][j] = load(batch[3 * i + j], p);
  return a;
}

inline void store_symmetric(const Matrix3<PointVec>& s, double (&batch)[9][StressBatch::kCapacity], int p) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) store(i <= j ? s.m[i][j] : s.m[j][i], batch[3 * i + j], p);
}

inline void store_admissible(const PointMask& admissible, bool (&batch)[StressBatch::kCapacity], int p) {
  alignas(64) double lanes[StressBatch::kCapacity];
  store(zero_unless(admissible, PointVec(1.0)), lanes, 0);
  for (int i = 0; i < kPassLanes; ++i) batch[p + i] = lanes[i] != 0.0;
}

// The batch's stresses, kPassLanes points a pass; refused points get S = 0 and admissible = false.
template <class Law>
void law_stress_batch(const Law& law, StressBatch& batch) {
  for (int p = 0; p < StressBatch::kCapacity; p += kPassLanes) {
    const LawStress<PointVec> result = evaluate_stress(law, load_matrix(batch.F, p));
    store_symmetric(result.S, batch.S, p);
    store_admissible(result.admissible, batch.admissible, p);
  }
}

}  // namespace mtled::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#endif  // MTLED_LAW_STRESS_BATCH_INL_H_

// A law's stress_batch(), once per target: `function` in mtled::HWY_NAMESPACE.
#undef MTLED_LAW_STRESS_BATCH
#define MTLED_LAW_STRESS_BATCH(Law, function)                                                  \
  HWY_BEFORE_NAMESPACE();                                                                      \
  namespace mtled::HWY_NAMESPACE {                                                             \
  void function(const Law& law, ::mtled::StressBatch& batch) { law_stress_batch(law, batch); } \
  }                                                                                            \
  HWY_AFTER_NAMESPACE();
// Once (under HWY_ONCE): mtled::function, which runs the best target's.
#undef MTLED_LAW_STRESS_BATCH_DISPATCH
#define MTLED_LAW_STRESS_BATCH_DISPATCH(Law, function)                                                       \
  namespace mtled {                                                                                          \
  HWY_EXPORT(function);                                                                                      \
  void function(const Law& law, StressBatch& batch) noexcept { HWY_DYNAMIC_DISPATCH(function)(law, batch); } \
  }
