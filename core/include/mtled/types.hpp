#pragma once
#include <Eigen/Dense>
#include <cstddef>
#include <cstdint>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace mtled {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

// Node, integration-point and tet indices. 32 bits cover meshes far beyond what fits in memory here.
using Index = std::int32_t;

// Integration points first .. second - 1.
using PointRange = std::pair<Index, Index>;

// The force kernel's arrays: at least 64-byte aligned (a cache line, and the widest SIMD register, for aligned vector
// loads); from 2 MiB up, on 2 MiB boundaries in whole 2 MiB pages with transparent huge pages asked for (Linux
// madvise), so that streaming them walks the page tables 512 times less often. Defined in core/src/memory.cpp.
void* allocate_kernel_array(std::size_t bytes);
void free_kernel_array(void* p, std::size_t bytes) noexcept;

template <class T>
struct CacheLineAllocator {
  using value_type = T;
  CacheLineAllocator() = default;
  template <class U>
  CacheLineAllocator(const CacheLineAllocator<U>&) noexcept {}
  T* allocate(std::size_t n) { return static_cast<T*>(allocate_kernel_array(n * sizeof(T))); }
  void deallocate(T* p, std::size_t n) noexcept { free_kernel_array(p, n * sizeof(T)); }
  template <class U>
  bool operator==(const CacheLineAllocator<U>&) const noexcept {
    return true;
  }
};
template <class T>
using AlignedVector = std::vector<T, CacheLineAllocator<T>>;

// A CacheLineAllocator whose resize() leaves trivial elements unwritten: for arrays whose owner then writes every
// element itself, in parallel, so that the pages are first touched (mapped and cleared by the operating system) by
// all threads at once rather than by a serial zero-fill before them.
template <class T>
struct UnfilledAllocator : CacheLineAllocator<T> {
  UnfilledAllocator() = default;
  template <class U>
  UnfilledAllocator(const UnfilledAllocator<U>&) noexcept {}
  // Value-initialisation (resize's) becomes default-initialisation: no write for trivial types. Construction with
  // arguments is std::allocator_traits' own.
  template <class U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
    ::new (static_cast<void*>(p)) U;
  }
};
template <class T>
using UnfilledVector = std::vector<T, UnfilledAllocator<T>>;

}  // namespace mtled
