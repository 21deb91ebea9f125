// hal/large_array.hpp: large arrays on 2 MiB boundaries, advised for transparent huge pages.
#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <numeric>
#include <sstream>
#include <string>

#include "hal/large_array.hpp"

namespace {

// The VmFlags of the mapping of /proc/self/smaps that holds address a ("" if none was found).
std::string vm_flags_of(const void* a) {
  std::ifstream smaps("/proc/self/smaps");
  const auto x = reinterpret_cast<std::uintptr_t>(a);
  std::string line;
  bool inside = false;
  while (std::getline(smaps, line)) {
    std::uintptr_t lo = 0, hi = 0;
    char dash = 0;
    std::istringstream head(line);
    // A mapping's header ("lo-hi perms offset dev inode path"); its fields ("Size: ...") have
    // their colon before the first space.
    if (head >> std::hex >> lo >> dash >> hi && dash == '-' && line.find(':') > line.find(' ')) {
      inside = lo <= x && x < hi;
      continue;
    }
    if (inside && line.rfind("VmFlags:", 0) == 0) return line;
  }
  return "";
}

}  // namespace

TEST(LargeArray, SmallAllocationsAreOrdinaryMemory) {
  void* p = hal::allocate_large(1000);
  ASSERT_NE(p, nullptr);
  std::fill_n(static_cast<char*>(p), 1000, 'x');
  hal::deallocate_large(p, 1000);
  hal::deallocate_large(nullptr, 1000);  // like operator delete: nothing
}

TEST(LargeArray, LargeAllocationsLieOnHugePageBoundariesAdvisedForHugePages) {
  const std::size_t bytes = 5 * hal::kHugePageBytes + 12345;  // not a whole number of pages
  void* p = hal::allocate_large(bytes);
  ASSERT_NE(p, nullptr);
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(p) % hal::kHugePageBytes, 0u);
  std::fill_n(static_cast<unsigned char*>(p), bytes, 0xA5);  // every byte asked for is there
  std::ifstream thp("/sys/kernel/mm/transparent_hugepage/enabled");
  const std::string flags = vm_flags_of(p);
  if (!thp || flags.empty()) {
    hal::deallocate_large(p, bytes);
    GTEST_SKIP() << "no transparent huge pages in this kernel or no /proc/self/smaps: the advice cannot be seen";
  }
  // "hg": the mapping is advised MADV_HUGEPAGE (proc(5)), whatever the kernel's global mode.
  EXPECT_NE((flags + " ").find(" hg "), std::string::npos) << flags;
  hal::deallocate_large(p, bytes);
}

TEST(LargeArray, LargeVectorHoldsItsValuesThroughGrowthAndCopies) {
  hal::LargeVector<double> v;
  for (int k = 0; k < 700000; ++k) v.push_back(0.5 * k);  // grows past 2 MiB: regions replaced as it grows
  ASSERT_EQ(v.size(), 700000u);
  EXPECT_EQ(v[123456], 61728.0);
  const hal::LargeVector<double> copy = v;
  EXPECT_EQ(copy, v);
  v.resize(10);
  v.shrink_to_fit();
  EXPECT_EQ(std::accumulate(v.begin(), v.end(), 0.0), 22.5);
  EXPECT_EQ(copy.size(), 700000u);
}
