#pragma once
#include <Eigen/Dense>
#include <cstddef>
#include <cstdint>
#include <new>
#include <utility>
#include <vector>

namespace mtled {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

// Node, integration-point and tet indices. 32 bits cover meshes far beyond what fits in memory here.
using Index = std::int32_t;

// Integration points first .. second - 1.
using PointRange = std::pair<Index, Index>;

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
