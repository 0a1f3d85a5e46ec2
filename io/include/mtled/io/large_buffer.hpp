#pragma once
// Buffers of hundreds of megabytes (a field on an image grid, its scratch) first touched one page at a time: with
// 4 KiB pages that is one page fault per 4 KiB, and on a virtual machine a fault costs microseconds (half a million
// of them took 4 of the 17 s of a 256^3 field). This allocator asks Linux for transparent huge pages (madvise
// MADV_HUGEPAGE on 2 MiB-aligned memory), one fault per 2 MiB where the kernel allows it; elsewhere, and for small
// buffers, it is plain operator new.
#include <cstddef>
#include <cstdlib>
#include <new>
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
  bool operator==(const HugePageAllocator<U>&) const noexcept {
    return true;
  }
};

template <class T>
using LargeVector = std::vector<T, HugePageAllocator<T>>;

}  // namespace mtled
