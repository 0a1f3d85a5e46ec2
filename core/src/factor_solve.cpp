// The sparse LDL^T solves of factor_solve.hpp, compiled once per instruction set by hwy/foreach_target.h.
//
// Each row's components are one short vector (a record), so that a pass over L's entries serves them all: per entry
// one index, one value broadcast and one vector multiply-add, where the scalar loops did it per component. The
// forward pass (L^-1, by column) subtracts each entry's share from its row's record; the backward pass (L^-T) sums each
// column's entries into four partial sums in turn, added in a fixed order at the end: one chain of additions per
// column, whose latency bound that pass, becomes four independent chains.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "factor_solve.cpp"
#include "factor_solve.hpp"

#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace mtled::HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

template <std::size_t K>
static void SolveComponents(const factor_solve::LdltFactor& factor, const std::size_t* rows, double* y, double* x) {
  constexpr std::size_t W = factor_solve::record_width(K);
  const hn::CappedTag<double, W> d;
  using V = hn::Vec<decltype(d)>;
  const std::size_t lanes = hn::Lanes(d);
  constexpr std::size_t kMaxParts = W;  // a record is W / lanes vectors (1 where a vector holds W doubles)
  const std::size_t parts = W / lanes;
  const std::size_t n = factor.size;
  const int* offsets = factor.column_offsets;
  const int* row_index = factor.row_index;
  const double* value = factor.value;
  for (std::size_t i = 0; i < n; ++i) {
    double* record = x + W * static_cast<std::size_t>(factor.permutation[i]);
    for (std::size_t j = 0; j < W; ++j) record[j] = j < K ? y[K * rows[i] + j] : 0.0;
  }
  for (std::size_t col = 0; col < n; ++col) {
    V xc[kMaxParts];
    for (std::size_t k = 0; k < parts; ++k) xc[k] = hn::LoadU(d, x + W * col + k * lanes);
    for (int p = offsets[col]; p < offsets[col + 1]; ++p) {
      double* record = x + W * static_cast<std::size_t>(row_index[p]);
      const V l = hn::Set(d, value[p]);
      for (std::size_t k = 0; k < parts; ++k)
        hn::StoreU(hn::NegMulAdd(l, xc[k], hn::LoadU(d, record + k * lanes)), d, record + k * lanes);
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    const V scale = hn::Set(d, factor.inverse_diagonal[i]);
    for (std::size_t k = 0; k < parts; ++k)
      hn::StoreU(hn::Mul(scale, hn::LoadU(d, x + W * i + k * lanes)), d, x + W * i + k * lanes);
  }
  constexpr int kSums = 4;
  for (std::size_t col = n; col-- > 0;) {
    V sum[kSums][kMaxParts];
    for (auto& partial : sum)
      for (std::size_t k = 0; k < parts; ++k) partial[k] = hn::Zero(d);
    const auto add_entry = [&](int p, V(&partial)[kMaxParts]) {
      const double* record = x + W * static_cast<std::size_t>(row_index[p]);
      const V l = hn::Set(d, value[p]);
      for (std::size_t k = 0; k < parts; ++k) partial[k] = hn::MulAdd(l, hn::LoadU(d, record + k * lanes), partial[k]);
    };
    int p = offsets[col];
    const int end = offsets[col + 1];
    for (; p + kSums <= end; p += kSums)
      for (int s = 0; s < kSums; ++s) add_entry(p + s, sum[s]);
    // The last entries (fewer than kSums) into the first sums, each sum named at compile time: an index known only at
    // run time would keep the sums in memory instead of registers.
    if (p < end) add_entry(p, sum[0]);
    if (p + 1 < end) add_entry(p + 1, sum[1]);
    if (p + 2 < end) add_entry(p + 2, sum[2]);
    for (std::size_t k = 0; k < parts; ++k) {
      const V total = hn::Add(hn::Add(sum[0][k], sum[1][k]), hn::Add(sum[2][k], sum[3][k]));
      hn::StoreU(hn::Sub(hn::LoadU(d, x + W * col + k * lanes), total), d, x + W * col + k * lanes);
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    const double* record = x + W * static_cast<std::size_t>(factor.permutation[i]);
    for (std::size_t j = 0; j < K; ++j) y[K * rows[i] + j] = record[j];
  }
}

void Solve(const factor_solve::LdltFactor& factor, const std::size_t* rows, std::size_t components, double* y,
           double* scratch) {
  if (components == 1) return SolveComponents<1>(factor, rows, y, scratch);
  if (components == 2) return SolveComponents<2>(factor, rows, y, scratch);
  SolveComponents<3>(factor, rows, y, scratch);
}

}  // namespace mtled::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace mtled::factor_solve {
HWY_EXPORT(Solve);
void solve(const LdltFactor& factor, const std::size_t* rows, std::size_t components, double* y, double* scratch) {
  HWY_DYNAMIC_DISPATCH(Solve)(factor, rows, components, y, scratch);
}
}  // namespace mtled::factor_solve
#endif
