// The force kernel's vectorised parts (force_passes.hpp). Compiled once per instruction set by
// hwy/foreach_target.h, which re-includes this file; HWY_DYNAMIC_DISPATCH picks the CPU's best at run time.
//
// Vectors of (at most) 4 doubles, one lane per support entry of a row. On AVX2 and AVX-512 a node's record
// (x, y, z, 0) is one such vector: the displacements of 4 entries (and the nodes' corrections, where the scatter
// forms its test gradients) are read as 4 loads and a transpose, and their forces added back as a transpose and 4
// read-modify-writes, which is faster than the gather and scatter instructions (and AVX2 has no scatter); 512-bit
// vectors would not be faster here, since the wider cores split them in two halves anyway. Narrower targets gather
// and add lane by lane.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "force_passes.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

#include "force_passes.hpp"

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

// The entries' node records (at base + offsets[e]) += (x, y, z) of each lane.
HWY_INLINE void add_to_records(D d, V x, V y, V z, const Index* offsets, double* base) {
  const auto zero = hn::Zero(d);
  const auto xy_even = hn::InterleaveLower(x, y), xy_odd = hn::InterleaveUpper(d, x, y);
  const auto z_even = hn::InterleaveLower(z, zero), z_odd = hn::InterleaveUpper(d, z, zero);
  const V entry[4] = {hn::ConcatLowerLower(d, z_even, xy_even), hn::ConcatLowerLower(d, z_odd, xy_odd),
                      hn::ConcatUpperUpper(d, z_even, xy_even), hn::ConcatUpperUpper(d, z_odd, xy_odd)};
  for (int e = 0; e < 4; ++e) {
    double* record = base + offsets[e];
    hn::Store(hn::Add(hn::Load(d, record), entry[e]), d, record);
  }
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

HWY_INLINE void add_to_records(D d, V x, V y, V z, const Index* offsets, double* base) {
  double lanes[3][hn::MaxLanes(D())];
  hn::StoreU(x, d, lanes[0]);
  hn::StoreU(y, d, lanes[1]);
  hn::StoreU(z, d, lanes[2]);
  for (std::size_t e = 0; e < hn::Lanes(d); ++e) {
    double* record = base + offsets[e];
    for (int i = 0; i < 3; ++i) record[i] += lanes[i][e];
  }
}
#endif

// One row's blocks (gradients and records, RowBlock) as raw pointers, for loops that step through them (in locals:
// the compiler cannot tell that the kernel's stores do not move the rows' arrays, and would reload them after every
// store).
template <class Real>
struct RowBlocks {
  const RowBlock<Real>* begin;
  const RowBlock<Real>* end;
};
template <class Real>
HWY_INLINE RowBlocks<Real> row_blocks(const GradientRows& rows, Index row) {
  return {rows.block<Real>(rows.block_begin(row)), rows.block<Real>(rows.block_end(row))};
}

// How far ahead of its reads the kernel asks the caches for a stream's lines: about one batch of rows (8 points of
// 30-50 entries), so that a line arrives while the batch before it is computed. The consecutive points' rows lie one
// after another, so one fixed distance serves every row; near the end the prefetches run past it (they never fault).
constexpr std::ptrdiff_t kPrefetchBytes = 4096;
// Asks for the lines of `bytes` bytes at kPrefetchBytes past p (one line for a single-precision block) into the L2, not
// the L1 (locality 2: prefetcht1 on x86, pldl2keep on Arm): into the L1, the kernel was 1.1-1.4x slower on a Zen 4 (on
// a Zen 3 no different; docs/performance.md, fourteenth and fifteenth sections), likely because the lines in flight
// then hold the L1's few miss buffers and share it with the node records the loops read at random. The address is
// formed as an integer: past the array's end a pointer may not point.
template <std::size_t bytes>
HWY_INLINE void prefetch_ahead(const void* p) {
  constexpr int kReadOnly = 0, kIntoL2 = 2;
  const std::uintptr_t ahead = reinterpret_cast<std::uintptr_t>(p) + kPrefetchBytes;
  for (std::size_t line = 0; line < bytes; line += 64)
    __builtin_prefetch(reinterpret_cast<const char*>(ahead + line), kReadOnly, kIntoL2);
}

// kLanes gradient components of consecutive entries as doubles (single-precision rows are widened on the way in).
// (Unaligned: a double-precision block is 112 bytes, so every other one starts off a 32-byte boundary.)
HWY_INLINE V load_gradients(D d, const double* g) { return hn::LoadU(d, g); }
HWY_INLINE V load_gradients(D d, const float* g) { return hn::PromoteTo(d, hn::LoadU(hn::Rebind<float, D>(), g)); }

template <class Real>
void gather_rows(const GradientRows& rows, const double* u4, Index first, StressBatch& batch) {
  const D d;
  constexpr double kIdentity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  for (int p = 0; p < StressBatch::kCapacity; ++p) {
    if (p >= batch.count) {
      for (int c = 0; c < 9; ++c) batch.F[c][p] = kIdentity[c];
      continue;
    }
    // One accumulator per component of F, one lane per support entry; the padding entries add 0 x 0.
    V f[9];
    for (auto& v : f) v = hn::Zero(d);
    const RowBlocks<Real> row = row_blocks<Real>(rows, first + p);
    for (const RowBlock<Real>* block = row.begin; block != row.end; ++block) {
      prefetch_ahead<sizeof(RowBlock<Real>)>(block);
      for (int j = 0; j < kBlock; j += static_cast<int>(hn::Lanes(d))) {
        V u[3];
        load_records(d, u4, block->records + j, u[0], u[1], u[2]);
        const V grad[3] = {load_gradients(d, block->gradients[0] + j), load_gradients(d, block->gradients[1] + j),
                           load_gradients(d, block->gradients[2] + j)};
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

void Gather(const GradientRows& rows, const double* u4, Index first, StressBatch& batch) {
  if (rows.precision() == RowPrecision::single_precision)
    gather_rows<float>(rows, u4, first, batch);
  else
    gather_rows<double>(rows, u4, first, batch);
}

void FirstPiola(const StressBatch& batch, const double* weights, double (&P)[9][StressBatch::kCapacity]) {
  const hn::ScalableTag<double> d;
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
}

// f4 += the 3 x 4 forces of the entries at `records` (their test gradients t by component: x, y, z of the lanes).
HWY_INLINE void add_entry_forces(D d, const V (&stress)[9], const V (&t)[3], const Index* records, double* f4) {
  V force[3];
  for (int i = 0; i < 3; ++i)
    force[i] = hn::MulAdd(stress[3 * i + 2], t[2], hn::MulAdd(stress[3 * i + 1], t[1], hn::Mul(stress[3 * i], t[0])));
  add_to_records(d, force[0], force[1], force[2], records, f4);
}

// The scatter where the rows store the test gradients (single precision): their stream and the blocks' records (in
// cache: the gather has just read them), no per-node reads.
template <class Real>
void scatter_stored_tests(const GradientRows& rows, Index first, int count,
                          const double (&P)[9][StressBatch::kCapacity], const bool* skip, double* f4) {
  const D d;
  constexpr std::size_t kTestBlockBytes = 3 * kBlock * sizeof(Real);
  for (int p = 0; p < count; ++p) {
    if (skip[p]) continue;
    V stress[9];
    for (int c = 0; c < 9; ++c) stress[c] = hn::Set(d, P[c][p]);
    const RowBlocks<Real> row = row_blocks<Real>(rows, first + p);
    const Real* t = rows.block_test_gradients<Real>(rows.block_begin(first + p));
    for (const RowBlock<Real>* block = row.begin; block != row.end; ++block, t += 3 * kBlock) {
      prefetch_ahead<kTestBlockBytes>(t);
      for (int j = 0; j < kBlock; j += static_cast<int>(hn::Lanes(d))) {
        const V test[3] = {load_gradients(d, t + j), load_gradients(d, t + kBlock + j),
                           load_gradients(d, t + 2 * kBlock + j)};
        add_entry_forces(d, stress, test, block->records + j, f4);
      }
    }
  }
}

// The scatter that forms t = grad N + xi - m itself (double precision: a stored copy would double the bytes the
// kernel streams per entry, which costs more than the instructions it saves). The blocks are in cache (the gather
// has just read them); the nodes' corrections are read like the displacements.
template <class Real>
void scatter_formed_tests(const GradientRows& rows, const double* xi4, const double* m3, Index first, int count,
                          const double (&P)[9][StressBatch::kCapacity], const bool* skip, double* f4) {
  const D d;
  for (int p = 0; p < count; ++p) {
    if (skip[p]) continue;
    V stress[9], mean[3];
    for (int c = 0; c < 9; ++c) stress[c] = hn::Set(d, P[c][p]);
    for (int k = 0; k < 3; ++k) mean[k] = hn::Set(d, m3[3 * static_cast<std::size_t>(first + p) + k]);
    const RowBlocks<Real> row = row_blocks<Real>(rows, first + p);
    for (const RowBlock<Real>* block = row.begin; block != row.end; ++block)
      for (int j = 0; j < kBlock; j += static_cast<int>(hn::Lanes(d))) {
        V test[3];
        load_records(d, xi4, block->records + j, test[0], test[1], test[2]);
        for (int k = 0; k < 3; ++k)
          test[k] = hn::Add(load_gradients(d, block->gradients[k] + j), hn::Sub(test[k], mean[k]));
        add_entry_forces(d, stress, test, block->records + j, f4);
      }
  }
}

void Scatter(const GradientRows& rows, const double* xi4, const double* m3, Index first, int count,
             const double (&P)[9][StressBatch::kCapacity], const bool* skip, double* f4) {
  // Only single-precision rows store their test gradients (Discretisation::build_integration_correction), and only
  // where consistent integration corrects them (without it xi and m are zero, and the formed ones are the gradients).
  if (rows.precision() == RowPrecision::double_precision)
    scatter_formed_tests<double>(rows, xi4, m3, first, count, P, skip, f4);
  else if (rows.has_own_test_gradients())
    scatter_stored_tests<float>(rows, first, count, P, skip, f4);
  else
    scatter_formed_tests<float>(rows, xi4, m3, first, count, P, skip, f4);
}

}  // namespace mtled::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace mtled::force_passes {
HWY_EXPORT(Gather);
HWY_EXPORT(FirstPiola);
HWY_EXPORT(Scatter);

void gather(const GradientRows& rows, const double* u4, Index first, StressBatch& batch) {
  HWY_DYNAMIC_DISPATCH(Gather)(rows, u4, first, batch);
}
void first_piola(const StressBatch& batch, const double* weights, double (&P)[9][StressBatch::kCapacity]) {
  HWY_DYNAMIC_DISPATCH(FirstPiola)(batch, weights, P);
}
void scatter(const GradientRows& rows, const double* xi4, const double* m3, Index first, int count,
             const double (&P)[9][StressBatch::kCapacity], const bool* skip, double* f4) {
  HWY_DYNAMIC_DISPATCH(Scatter)(rows, xi4, m3, first, count, P, skip, f4);
}
}  // namespace mtled::force_passes
#endif
