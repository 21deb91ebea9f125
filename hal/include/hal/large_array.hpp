// Memory for the few large arrays a host run fills once and reads many times: the Monte Carlo's
// shared truth track (1.8 M IMU increments, 115 MB for the 1800 s flight) and a recording's IMU
// samples (the same size). An allocation of at least kHugePageBytes is placed on a 2 MiB boundary,
// rounded up to whole 2 MiB pages and advised MADV_HUGEPAGE, so that the kernel backs it with
// transparent huge pages where it allows them (/sys/kernel/mm/transparent_hugepage/enabled
// "always" or "madvise"). Filling 115 MB then takes about 60 page faults instead of about 29,000;
// on the VM of docs/performance.md ("Large arrays on huge pages") a 4 KiB fault cost about 10 us,
// and the track's first touch was a third of a one-run Monte Carlo's wall time. The advice changes
// where the bytes live, never their values. Where huge pages are off (or madvise refuses), the
// memory is ordinary pages and works the same.
//
// Smaller allocations go to plain ::operator new. Failure is std::bad_alloc from the standard
// library's operator new, as for any std::vector (host side only; fsw/ allocates nothing).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace hal {

/// The huge page size these allocations are aligned to and rounded up to.
inline constexpr std::size_t kHugePageBytes = std::size_t{2} << 20;

/// bytes of memory, 2 MiB-aligned and advised MADV_HUGEPAGE from kHugePageBytes up (the region
/// rounded up to whole huge pages); plain ::operator new below. Free with deallocate_large(p, bytes).
void* allocate_large(std::size_t bytes);
/// Frees what allocate_large(bytes) returned (the same bytes).
void deallocate_large(void* p, std::size_t bytes) noexcept;

/// A standard allocator on allocate_large(): for std::vector (LargeVector) of large arrays.
template <class T>
struct LargeArrayAllocator {
  using value_type = T;
  LargeArrayAllocator() noexcept = default;
  template <class U>
  LargeArrayAllocator(const LargeArrayAllocator<U>&) noexcept {}  // NOLINT: rebinding is implicit
  T* allocate(std::size_t n) {  // an impossible n asks for SIZE_MAX bytes: operator new's std::bad_alloc
    return static_cast<T*>(allocate_large(n > SIZE_MAX / sizeof(T) ? SIZE_MAX : n * sizeof(T)));
  }
  void deallocate(T* p, std::size_t n) noexcept { deallocate_large(p, n * sizeof(T)); }
  template <class U>
  bool operator==(const LargeArrayAllocator<U>&) const noexcept {
    return true;
  }
};

/// A std::vector whose storage is allocate_large()'s.
template <class T>
using LargeVector = std::vector<T, LargeArrayAllocator<T>>;

}  // namespace hal
