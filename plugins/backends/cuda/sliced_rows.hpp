#pragma once
// The sliced ELLPACK rows both the host layout (device_layout.hpp) and the kernels (kernels.cu) speak: slices of
// kSlice consecutive rows, each slice padded to its longest row, its elements stored entry by entry so that the
// kSlice threads of a warp read consecutive addresses.
#include <cstdint>
#include <vector>

namespace mtled::cuda {

constexpr int kSlice = 32;

template <class Real>
struct SlicedRows {
  std::vector<std::int64_t> slice_begin;  // slices + 1 values: slice s holds elements slice_begin[s] .. slice_begin[s+1]-1
  std::vector<std::int32_t> column;       // element slice_begin[s] + k kSlice + lane: entry k of the slice's row `lane`
  std::vector<Real> gx, gy, gz;           // the gradient of each element (0 on padding)
  std::vector<std::int32_t> row;          // per slice lane (slices x kSlice): the row it holds, -1 for none
  std::int64_t entries = 0;               // real entries, padding excluded

  std::int64_t slices() const { return static_cast<std::int64_t>(slice_begin.size()) - 1; }
  std::int64_t elements() const { return slice_begin.empty() ? 0 : slice_begin.back(); }
};

}  // namespace mtled::cuda
