#include <new>

#include "mtled/types.hpp"

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace mtled {
namespace {

constexpr std::size_t kHugePage = std::size_t{2} << 20;
constexpr std::align_val_t kCacheLine{64};

bool huge(std::size_t bytes) { return bytes >= kHugePage; }
std::size_t whole_huge_pages(std::size_t bytes) { return (bytes + kHugePage - 1) / kHugePage * kHugePage; }

}  // namespace

void* allocate_kernel_array(std::size_t bytes) {
  if (!huge(bytes)) return ::operator new(bytes, kCacheLine);
  const std::size_t length = whole_huge_pages(bytes);
  void* p = ::operator new(length, std::align_val_t{kHugePage});
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  // A request, not a requirement: where the kernel has transparent huge pages off (or always on), nothing changes.
  (void)madvise(p, length, MADV_HUGEPAGE);
#endif
  return p;
}

void free_kernel_array(void* p, std::size_t bytes) noexcept {
  if (!huge(bytes))
    ::operator delete(p, kCacheLine);
  else
    ::operator delete(p, std::align_val_t{kHugePage});
}

}  // namespace mtled
