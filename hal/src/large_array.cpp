// hal/large_array.hpp: 2 MiB-aligned allocations advised for transparent huge pages.
#include "hal/large_array.hpp"

#include <sys/mman.h>

#include <cstdint>
#include <new>

namespace hal {
namespace {

// bytes rounded up to whole huge pages; a size too large to round is left as it is (operator new
// then fails with std::bad_alloc).
std::size_t rounded_to_huge_pages(std::size_t bytes) {
  const std::size_t rest = bytes % kHugePageBytes;
  if (rest == 0 || bytes > SIZE_MAX - kHugePageBytes) return bytes;
  return bytes + (kHugePageBytes - rest);
}

}  // namespace

void* allocate_large(std::size_t bytes) {
  if (bytes < kHugePageBytes) return ::operator new(bytes);
  const std::size_t region = rounded_to_huge_pages(bytes);
  void* p = ::operator new(region, std::align_val_t{kHugePageBytes});
  // Advice only: refused (huge pages off, an old kernel), the region is ordinary pages and the
  // same memory; nothing to report or undo.
  (void)::madvise(p, region, MADV_HUGEPAGE);
  return p;
}

void deallocate_large(void* p, std::size_t bytes) noexcept {
  if (bytes < kHugePageBytes) {
    ::operator delete(p);
    return;
  }
  ::operator delete(p, std::align_val_t{kHugePageBytes});
}

}  // namespace hal
