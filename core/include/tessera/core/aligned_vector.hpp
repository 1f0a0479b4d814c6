// AlignedVector<T>: a std::vector whose storage starts on a kSimdAlignment-byte boundary, so
// SIMD loads of its lanes never split a cache line. Every SoA array of the hot path uses it.
// Large allocations are advised to use huge pages (see huge_pages.hpp): these arrays are
// filled right after they are allocated.
#pragma once

#include <cstddef>
#include <new>
#include <vector>

#include <tessera/core/huge_pages.hpp>

namespace tessera {

/// Alignment of SoA arrays: one AVX-512 register, one cache line.
inline constexpr std::size_t kSimdAlignment = 64;

template <class T>
struct AlignedAllocator {
  using value_type = T;
  AlignedAllocator() noexcept = default;
  template <class U>
  AlignedAllocator(const AlignedAllocator<U>&) noexcept {}
  T* allocate(std::size_t n) {
    T* data = static_cast<T*>(::operator new(n * sizeof(T), std::align_val_t(kSimdAlignment)));
    advise_huge_pages(data, n * sizeof(T));
    return data;
  }
  void deallocate(T* p, std::size_t) noexcept {
    ::operator delete(p, std::align_val_t(kSimdAlignment));
  }
  template <class U>
  bool operator==(const AlignedAllocator<U>&) const noexcept {
    return true;
  }
};

template <class T>
using AlignedVector = std::vector<T, AlignedAllocator<T>>;

}  // namespace tessera
