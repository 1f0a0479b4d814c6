// Large arrays: make_large_vector fills like std::vector, advise_huge_pages accepts any range
// (small, unaligned, null), and where Linux offers transparent huge pages on advice the
// advised array is in fact backed by them (read back from /proc/self/smaps).
#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <tessera/core/aligned_vector.hpp>
#include <tessera/core/huge_pages.hpp>

namespace tessera {
namespace huge_pages_tests {

TEST(HugePages, LargeVectorsHoldWhatTheyWereGiven) {
  const std::vector<int> filled = make_large_vector<int>(3'000'000, 7);
  ASSERT_EQ(filled.size(), 3'000'000u);
  for (int v : filled) ASSERT_EQ(v, 7);
  const std::vector<int> small = make_large_vector<int>(5, -1);
  EXPECT_EQ(small, std::vector<int>(5, -1));
  EXPECT_TRUE(make_large_vector<double>(0).empty());
}

TEST(HugePages, AnyRangeIsAcceptedAsAHint) {
  advise_huge_pages(nullptr, 0);
  advise_huge_pages(nullptr, std::size_t(64) << 20);
  std::vector<char> bytes(5 << 20);
  advise_huge_pages(bytes.data() + 3, bytes.size() - 3);  // unaligned both ends
  advise_huge_pages(bytes.data(), 100);
  bytes.back() = 1;
  EXPECT_EQ(bytes.back(), 1);
}

/// "[madvise]" or "[always]" when the kernel backs advised anonymous memory with huge pages.
std::string transparent_huge_page_mode() {
  std::ifstream file("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string line;
  std::getline(file, line);
  for (const char* mode : {"[always]", "[madvise]"})
    if (line.find(mode) != std::string::npos) return mode;
  return "";
}

/// Kilobytes of AnonHugePages in the mapping of /proc/self/smaps that contains `address`.
long huge_kilobytes_at(const void* address) {
  std::ifstream smaps("/proc/self/smaps");
  const auto target = reinterpret_cast<std::uintptr_t>(address);
  bool inside = false;
  for (std::string line; std::getline(smaps, line);) {
    std::uintptr_t begin = 0, end = 0;
    char dash = 0;
    std::istringstream header(line);
    if (header >> std::hex >> begin >> dash >> end && dash == '-' &&
        line.find(':') > line.find(' ')) {
      inside = begin <= target && target < end;
      continue;
    }
    if (inside && line.rfind("AnonHugePages:", 0) == 0)
      return std::stol(line.substr(std::string("AnonHugePages:").size()));
  }
  return -1;
}

TEST(HugePages, AdvisedArraysAreBackedByHugePagesWhereTheKernelOffersThem) {
  if (transparent_huge_page_mode().empty())
    GTEST_SKIP() << "transparent huge pages are off on this machine";
  const std::vector<std::uint64_t> plain = make_large_vector<std::uint64_t>(std::size_t(4) << 20, 1);
  const long plain_kilobytes = huge_kilobytes_at(plain.data() + plain.size() / 2);
  AlignedVector<float> aligned(std::size_t(8) << 20, 1.0f);
  const long aligned_kilobytes = huge_kilobytes_at(aligned.data() + aligned.size() / 2);
  // 32 MiB each: at least a few of their 2 MiB pages must be huge (the kernel may fall back to
  // small pages for some when memory is fragmented).
  EXPECT_GE(plain_kilobytes, 2048) << transparent_huge_page_mode();
  EXPECT_GE(aligned_kilobytes, 2048) << transparent_huge_page_mode();
}

}  // namespace huge_pages_tests
}  // namespace tessera
