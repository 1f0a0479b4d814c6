// Internal: an array of trivially copyable values left uninitialised, advised for huge pages.
//
// Why: the start-up passes (stencil order, colour grouping) fill their arrays in parallel, each
// thread its own chunks. A std::vector would be zero-filled first by one thread, which on the
// 6.3 M-constraint cloth is a sequential write of tens of MB (and, on fresh memory, every page
// fault) before the parallel fill writes it all again.
#pragma once

#include <cstddef>
#include <memory>
#include <type_traits>

#include <tessera/core/huge_pages.hpp>

namespace tessera::detail {

template <class T>
class LargeBuffer {
  static_assert(std::is_trivially_copyable_v<T> && std::is_trivially_destructible_v<T>);

 public:
  LargeBuffer() = default;
  explicit LargeBuffer(std::size_t size) : data_(new T[size]), size_(size) {
    advise_huge_pages(data_.get(), size * sizeof(T));
  }
  T* data() { return data_.get(); }
  const T* data() const { return data_.get(); }
  std::size_t size() const { return size_; }
  T* begin() { return data_.get(); }
  T* end() { return data_.get() + size_; }
  const T* begin() const { return data_.get(); }
  const T* end() const { return data_.get() + size_; }
  T& operator[](std::size_t i) { return data_[i]; }
  const T& operator[](std::size_t i) const { return data_[i]; }

 private:
  std::unique_ptr<T[]> data_;
  std::size_t size_ = 0;
};

}  // namespace tessera::detail
