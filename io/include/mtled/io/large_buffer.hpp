#pragma once
// Buffers of hundreds of megabytes (a field on an image grid, its scratch) first touched one page at a time: with
// 4 KiB pages that is one page fault per 4 KiB, and on a virtual machine a fault costs microseconds (half a million
// of them took 4 of the 17 s of a 256^3 field). This allocator asks Linux for transparent huge pages (madvise
// MADV_HUGEPAGE on 2 MiB-aligned memory), one fault per 2 MiB where the kernel allows it; elsewhere, and for small
// buffers, it is plain operator new.
//
// A LargeVector's new elements are default-initialised, as by new T[n]: LargeVector<double>(n) and resize(n) leave
// numbers unset, so that the first touch of each page is the fill that follows, on every thread (large_vector() below)
// rather than a serial zeroing first. Fill what you size.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <new>
#include <utility>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace mtled {

template <class T>
struct HugePageAllocator {
  using value_type = T;
  static constexpr std::size_t kHugePage = std::size_t{2} << 20;

  HugePageAllocator() = default;
  template <class U>
  explicit HugePageAllocator(const HugePageAllocator<U>&) noexcept {}

  static bool huge(std::size_t bytes) { return bytes >= 2 * kHugePage; }
  static std::size_t rounded(std::size_t bytes) { return (bytes + kHugePage - 1) / kHugePage * kHugePage; }

  T* allocate(std::size_t n) {
    const std::size_t bytes = n * sizeof(T);
    if (!huge(bytes)) return static_cast<T*>(::operator new(bytes));
    void* memory = std::aligned_alloc(kHugePage, rounded(bytes));
    if (memory == nullptr) throw std::bad_alloc();
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    madvise(memory, rounded(bytes), MADV_HUGEPAGE);  // a hint: without it the buffer still works, with small pages
#endif
    return static_cast<T*>(memory);
  }
  void deallocate(T* memory, std::size_t n) noexcept {
    if (huge(n * sizeof(T)))
      std::free(memory);
    else
      ::operator delete(memory);
  }
  template <class U>
  void construct(U* at) noexcept {
    ::new (static_cast<void*>(at)) U;
  }
  template <class U, class... Arguments>
  void construct(U* at, Arguments&&... arguments) {
    ::new (static_cast<void*>(at)) U(std::forward<Arguments>(arguments)...);
  }
  template <class U>
  bool operator==(const HugePageAllocator<U>&) const noexcept {
    return true;
  }
};

template <class T>
using LargeVector = std::vector<T, HugePageAllocator<T>>;

// n copies of value, written on every thread (each thread first-touches its own pages).
template <class T>
LargeVector<T> large_vector(std::size_t n, const T& value) {
  LargeVector<T> out(n);
  const auto count = static_cast<std::int64_t>(n);
#pragma omp parallel for schedule(static)
  for (std::int64_t i = 0; i < count; ++i) out[static_cast<std::size_t>(i)] = value;
  return out;
}

}  // namespace mtled
