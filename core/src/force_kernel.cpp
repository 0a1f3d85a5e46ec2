// The force kernel's vectorised parts (force_kernel.hpp). Compiled once per instruction set by
// hwy/foreach_target.h, which re-includes this file; HWY_DYNAMIC_DISPATCH picks the CPU's best at run time.
//
// Vectors of (at most) 4 doubles. The gather takes one lane per support entry of a row: on AVX2 and AVX-512 a
// node's displacement record (x, y, z, 0) is one such vector, and the displacements of 4 entries are read as 4 loads
// and a transpose, which is faster than the gather instructions; narrower targets gather lane by lane. The node
// pass takes one lane per force component: a stress record's columns are such vectors. 512-bit vectors would not
// pay in either: the records are 4 doubles wide.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "force_kernel.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/cache_control.h>
#include <hwy/highway.h>

#include "force_kernel.hpp"

HWY_BEFORE_NAMESPACE();
namespace mtled::HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using D = hn::CappedTag<double, GradientRows::kBlock>;
using V = hn::Vec<D>;
constexpr int kBlock = GradientRows::kBlock;

#if HWY_TARGET == HWY_AVX2 || HWY_TARGET == HWY_AVX3 || HWY_TARGET == HWY_AVX3_DL
static_assert(hn::MaxLanes(D()) == 4);

// (x, y, z) of the entries' node records (at base + offsets[e]), one lane each.
HWY_INLINE void load_records(D d, const double* base, const Index* offsets, V& x, V& y, V& z) {
  const auto a = hn::Load(d, base + offsets[0]);
  const auto b = hn::Load(d, base + offsets[1]);
  const auto c = hn::Load(d, base + offsets[2]);
  const auto e = hn::Load(d, base + offsets[3]);
  const auto ab_even = hn::InterleaveLower(a, b), ab_odd = hn::InterleaveUpper(d, a, b);
  const auto ce_even = hn::InterleaveLower(c, e), ce_odd = hn::InterleaveUpper(d, c, e);
  x = hn::ConcatLowerLower(d, ce_even, ab_even);
  y = hn::ConcatLowerLower(d, ce_odd, ab_odd);
  z = hn::ConcatUpperUpper(d, ce_even, ab_even);
}

// The lane sums of f[0..8]: four at a time by a transpose and two additions instead of nine reductions.
HWY_INLINE void sum_lanes(D d, const V (&f)[9], double (&sums)[9]) {
  for (int first = 0; first < 8; first += 4) {
    const V a = f[first], b = f[first + 1], c = f[first + 2], e = f[first + 3];
    const V ab = hn::Add(hn::InterleaveLower(a, b), hn::InterleaveUpper(d, a, b));  // a0+a1 b0+b1 a2+a3 b2+b3
    const V ce = hn::Add(hn::InterleaveLower(c, e), hn::InterleaveUpper(d, c, e));
    hn::StoreU(hn::Add(hn::ConcatLowerLower(d, ce, ab), hn::ConcatUpperUpper(d, ce, ab)), d, sums + first);
  }
  sums[8] = hn::GetLane(hn::SumOfLanes(d, f[8]));
}
#else  // one or two lanes: gather, add lane by lane, reduce one by one
HWY_INLINE void sum_lanes(D d, const V (&f)[9], double (&sums)[9]) {
  for (int c = 0; c < 9; ++c) sums[c] = hn::GetLane(hn::SumOfLanes(d, f[c]));
}

HWY_INLINE void load_records(D d, const double* base, const Index* offsets, V& x, V& y, V& z) {
  const hn::RebindToSigned<D> di;
  const hn::Rebind<std::int32_t, D> d32;
  const auto index = hn::PromoteTo(di, hn::LoadU(d32, offsets));
  x = hn::GatherIndex(d, base, index);
  y = hn::GatherIndex(d, base + 1, index);
  z = hn::GatherIndex(d, base + 2, index);
}

#endif

// One row's blocks as raw pointers, for loops that step through them (in locals: the compiler cannot tell that
// the kernel's stores do not move the rows' arrays, and would reload them after every store). The loops step the
// two pointers and stop at records_end, which keeps one counter fewer than a block index.
template <class Real>
struct RowBlocks {
  const Real* gradients;  // 3 kBlock per block
  const Index* records;   // kBlock per block
  const Index* records_end;
};
template <class Real>
HWY_INLINE RowBlocks<Real> row_blocks(const GradientRows& rows, Index row) {
  const std::int64_t begin = rows.block_begin(row);
  return {rows.block_gradients<Real>(begin), rows.block_records(begin), rows.block_records(rows.block_end(row))};
}

// Asks the caches for one row (its gradients and record offsets), two 64-byte lines per turn of the loop (the
// loop's own instructions cost as much as the prefetches). The second line of the last turn may lie past the row:
// a prefetch never faults.
HWY_INLINE void prefetch_lines(const void* begin, const void* end) {
  for (const char* line = static_cast<const char*>(begin); line < static_cast<const char*>(end); line += 128) {
    hwy::Prefetch(line);
    hwy::Prefetch(line + 64);
  }
}
template <class Real>
HWY_INLINE void prefetch_row(const GradientRows& rows, Index row) {
  prefetch_lines(rows.block_gradients<Real>(rows.block_begin(row)), rows.block_gradients<Real>(rows.block_end(row)));
  prefetch_lines(rows.block_records(rows.block_begin(row)), rows.block_records(rows.block_end(row)));
}

// kLanes gradient components of consecutive entries as doubles (single-precision rows are widened on the way in).
HWY_INLINE V load_gradients(D d, const double* g) { return hn::Load(d, g); }
HWY_INLINE V load_gradients(D d, const float* g) { return hn::PromoteTo(d, hn::LoadU(hn::Rebind<float, D>(), g)); }

template <class Real>
void gather_rows(const GradientRows& rows, const double* u4, Index first, Index prefetch_end, StressBatch& batch) {
  const D d;
  constexpr double kIdentity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  for (int p = 0; p < StressBatch::kCapacity; ++p) {
    if (p >= batch.count) {
      for (int c = 0; c < 9; ++c) batch.F[c][p] = kIdentity[c];
      continue;
    }
    // The row one batch ahead starts streaming from memory while this batch is computed, one row per row, so
    // that the requests do not queue up.
    if (first + p + batch.count < prefetch_end) prefetch_row<Real>(rows, first + p + batch.count);
    // One accumulator per component of F, one lane per support entry; the padding entries add 0 x 0.
    V f[9];
    for (auto& v : f) v = hn::Zero(d);
    const RowBlocks<Real> row = row_blocks<Real>(rows, first + p);
    const Real* g = row.gradients;
    for (const Index* records = row.records; records != row.records_end; records += kBlock, g += 3 * kBlock) {
      for (int j = 0; j < kBlock; j += static_cast<int>(hn::Lanes(d))) {
        V u[3];
        load_records(d, u4, records + j, u[0], u[1], u[2]);
        const V grad[3] = {load_gradients(d, g + j), load_gradients(d, g + kBlock + j),
                           load_gradients(d, g + 2 * kBlock + j)};
        for (int i = 0; i < 3; ++i)
          for (int k = 0; k < 3; ++k) f[3 * i + k] = hn::MulAdd(u[i], grad[k], f[3 * i + k]);
      }
    }
    double sums[9];
    sum_lanes(d, f, sums);
    // The identity's nonzero entries only: x + 0.0 is not x for x = -0.0, so the compiler would keep six additions.
    for (int c = 0; c < 9; ++c) batch.F[c][p] = kIdentity[c] == 0.0 ? sums[c] : kIdentity[c] + sums[c];
  }
}

void Gather(const GradientRows& rows, const double* u4, Index first, Index prefetch_end, StressBatch& batch) {
  if (rows.precision() == RowPrecision::single_precision)
    gather_rows<float>(rows, u4, first, prefetch_end, batch);
  else
    gather_rows<double>(rows, u4, first, prefetch_end, batch);
}

void StoreStressRecords(const StressBatch& batch, const double* weights, const bool* skip, double* records) {
  const hn::ScalableTag<double> d;
  alignas(64) double P[9][StressBatch::kCapacity];
  for (int p = 0; p < StressBatch::kCapacity; p += static_cast<int>(hn::Lanes(d))) {
    const auto w = hn::LoadU(d, weights + p);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        auto sum = hn::Mul(hn::Load(d, &batch.F[3 * i][p]), hn::Load(d, &batch.S[j][p]));
        sum = hn::MulAdd(hn::Load(d, &batch.F[3 * i + 1][p]), hn::Load(d, &batch.S[3 + j][p]), sum);
        sum = hn::MulAdd(hn::Load(d, &batch.F[3 * i + 2][p]), hn::Load(d, &batch.S[6 + j][p]), sum);
        hn::Store(hn::Mul(w, sum), d, &P[3 * i + j][p]);
      }
  }
  // Column j of the record holds (P_0j, P_1j, P_2j); its fourth entry stays the zero it was allocated with.
  for (int p = 0; p < batch.count; ++p) {
    double* record = records + static_cast<std::size_t>(kStressRecord) * p;
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 3; ++i) record[4 * j + i] = skip[p] ? 0.0 : P[3 * i + j][p];
  }
}

// f_I = sum_p (w P)_p t_pI with the force's components in the lanes: per entry three multiply-adds of a record's
// columns by broadcast gradient components. Two entries at a time into separate accumulators (and one per column),
// so that consecutive multiply-adds do not wait for each other. Each node's sum runs in its entries' order: the
// same on every thread count.
template <class Real>
void node_forces_rows(const TestGradientRows& rows, const double* records, Index begin, Index end, double* f) {
  const D d;
  constexpr int kLanes = static_cast<int>(hn::MaxLanes(D()));
  constexpr int kParts = 4 / kLanes;  // vectors per record column (1 on AVX2 and AVX-512)
  const TestGradientEntry<Real>* entries = rows.data<Real>();
  for (Index node = begin; node < end; ++node) {
    V sum[2][3][kParts];
    for (auto& a : sum)
      for (auto& b : a)
        for (auto& c : b) c = hn::Zero(d);
    const TestGradientEntry<Real>* e = entries + rows.begin(node);
    const TestGradientEntry<Real>* const stop = entries + rows.end(node);
    const auto add = [&](const TestGradientEntry<Real>& entry, V(&to)[3][kParts]) {
      const double* record = records + entry.point_record;
      for (int j = 0; j < 3; ++j) {
        const V t = hn::Set(d, static_cast<double>(entry.gradient[j]));
        for (int h = 0; h < kParts; ++h) to[j][h] = hn::MulAdd(hn::Load(d, record + 4 * j + kLanes * h), t, to[j][h]);
      }
    };
    for (; stop - e >= 2; e += 2) {
      add(e[0], sum[0]);
      add(e[1], sum[1]);
    }
    if (e != stop) add(e[0], sum[0]);
    alignas(32) double total[4];
    for (int h = 0; h < kParts; ++h) {
      V v = hn::Add(hn::Add(sum[0][0][h], sum[1][0][h]), hn::Add(sum[0][1][h], sum[1][1][h]));
      v = hn::Add(v, hn::Add(sum[0][2][h], sum[1][2][h]));
      hn::Store(v, d, total + kLanes * h);
    }
    for (int c = 0; c < 3; ++c) f[3 * static_cast<std::size_t>(node) + c] = total[c];
  }
}

void NodeForces(const TestGradientRows& rows, const double* records, Index begin, Index end, double* f) {
  if (rows.precision() == RowPrecision::single_precision)
    node_forces_rows<float>(rows, records, begin, end, f);
  else
    node_forces_rows<double>(rows, records, begin, end, f);
}

}  // namespace mtled::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace mtled::force_kernel {
HWY_EXPORT(Gather);
HWY_EXPORT(StoreStressRecords);
HWY_EXPORT(NodeForces);

void gather(const GradientRows& rows, const double* u4, Index first, Index prefetch_end, StressBatch& batch) {
  HWY_DYNAMIC_DISPATCH(Gather)(rows, u4, first, prefetch_end, batch);
}
void store_stress_records(const StressBatch& batch, const double* weights, const bool* skip, double* records) {
  HWY_DYNAMIC_DISPATCH(StoreStressRecords)(batch, weights, skip, records);
}
void node_forces(const TestGradientRows& rows, const double* records, Index begin, Index end, double* f) {
  HWY_DYNAMIC_DISPATCH(NodeForces)(rows, records, begin, end, f);
}
}  // namespace mtled::force_kernel
#endif
