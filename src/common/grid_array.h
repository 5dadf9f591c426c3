#pragma once
// A grid-sized array whose pages are first touched by the threads that fill it: a std::vector zeroes all of
// them on one thread first (on maltoporin's 53M voxels 0.2-0.3 s a float array, fresh pages costing this
// machine ~2 GB/s, the other core idle). Private to src/.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstddef>
#include <memory>

namespace chokeloops::detail {

template <class T>
class GridArray {
 public:
  GridArray() = default;
  // Not initialised (new T[n] on a trivial T touches nothing): for a caller that writes every element it
  // reads, in parallel.
  explicit GridArray(std::size_t n) : data_(new T[n]), size_(n) {}
  // Every element `value`, written in parallel.
  GridArray(std::size_t n, T value) : GridArray(n) {
    T* d = data_.get();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, std::size_t(1) << 16),
                      [&](const tbb::blocked_range<std::size_t>& r) { std::fill(d + r.begin(), d + r.end(), value); });
  }
  T& operator[](std::size_t i) { return data_[i]; }
  const T& operator[](std::size_t i) const { return data_[i]; }
  T* data() { return data_.get(); }
  const T* data() const { return data_.get(); }
  std::size_t size() const { return size_; }

 private:
  std::unique_ptr<T[]> data_;
  std::size_t size_ = 0;
};

}  // namespace chokeloops::detail
