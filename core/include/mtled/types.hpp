#pragma once
#include <Eigen/Dense>
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <new>
#include <span>
#include <utility>
#include <vector>

namespace mtled {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

// Node, integration-point and tet indices. 32 bits cover meshes far beyond what fits in memory here.
using Index = std::int32_t;

// Integration points first .. second - 1.
using PointRange = std::pair<Index, Index>;

// body(begin, end) over share `part` of `parts` of the ranges' points taken in order (contiguous equal shares, as
// ThreadTeam::share splits one range), one call per range the share meets.
template <class Body>
void for_each_piece_of_share(std::span<const PointRange> ranges, int part, int parts, Body&& body) {
  std::int64_t n = 0;
  for (const PointRange& range : ranges) n += range.second - range.first;
  const std::int64_t begin = n * part / parts, end = n * (part + 1) / parts;
  std::int64_t offset = 0;  // of the current range among the ranges' points
  for (const PointRange& range : ranges) {
    const std::int64_t size = range.second - range.first;
    const std::int64_t from = std::max<std::int64_t>(begin - offset, 0), to = std::min<std::int64_t>(end - offset, size);
    if (from < to) body(static_cast<Index>(range.first + from), static_cast<Index>(range.first + to));
    offset += size;
  }
}

// Allocates on 64-byte boundaries (a cache line, and the widest SIMD register), for the arrays the force
// kernel reads with aligned vector loads.
template <class T>
struct CacheLineAllocator {
  using value_type = T;
  static constexpr std::align_val_t kAlignment{64};
  CacheLineAllocator() = default;
  template <class U>
  CacheLineAllocator(const CacheLineAllocator<U>&) noexcept {}
  T* allocate(std::size_t n) { return static_cast<T*>(::operator new(n * sizeof(T), kAlignment)); }
  void deallocate(T* p, std::size_t) noexcept { ::operator delete(p, kAlignment); }
  template <class U>
  bool operator==(const CacheLineAllocator<U>&) const noexcept {
    return true;
  }
};
template <class T>
using AlignedVector = std::vector<T, CacheLineAllocator<T>>;

}  // namespace mtled
