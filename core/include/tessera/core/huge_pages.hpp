// Huge pages for large arrays that are filled as soon as they are allocated.
//
// Why: the first write to fresh memory costs a page fault per page. With 4 KiB pages that is
// 256 faults per MiB, and under a hypervisor each fault is dear: on the development machine (a
// Firecracker VM) filling fresh memory costs 3.3 ms per MiB, so colouring a 6.3 M-constraint
// cloth spent two thirds of its time faulting in its ~60 MB of output and work arrays. Backed
// by 2 MiB transparent huge pages the same fill costs 0.09 ms per MiB. Linux hands out huge
// pages to ranges advised with madvise(MADV_HUGEPAGE) when THP is in "madvise" mode (the
// common default) and to all memory in "always" mode; the advice is a hint, so a system
// without huge pages simply keeps using small ones.
//
// Only the 2 MiB-aligned interior of a range of at least 4 MiB is advised: small arrays would
// gain nothing and could be bloated to 2 MiB. Advice must come before the first touch, which
// is why make_large_vector reserves, advises, and only then fills.
#pragma once

#include <cstddef>
#include <vector>

namespace tessera {

/// Advises the kernel to back the 2 MiB-aligned part of [data, data + bytes) with huge pages
/// when bytes ≥ 4 MiB; does nothing for smaller ranges or where the hint is not available.
void advise_huge_pages(void* data, std::size_t bytes) noexcept;

/// `count` copies of `value` in storage advised before it is touched (see the file comment).
template <class T>
std::vector<T> make_large_vector(std::size_t count, const T& value = T()) {
  std::vector<T> result;
  result.reserve(count);
  advise_huge_pages(result.data(), count * sizeof(T));
  result.resize(count, value);
  return result;
}

}  // namespace tessera
