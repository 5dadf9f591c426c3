#pragma once
// The index of the first value that is not finite (NaN or an infinity) in v[0, n), or n when there is none.
// Parallel blocks are tested branch-free by their exponent bits and only one that holds such a value is
// searched: a serial scan of a 53M-voxel grid was 30-50 ms with the other core idle. Private to src/.
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>

namespace chokeloops::detail {

inline std::size_t first_non_finite(const float* v, std::size_t n) {
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, n, std::size_t(1) << 16), n,
      [&](const tbb::blocked_range<std::size_t>& r, std::size_t found) {
        if (found < r.begin()) return found;
        std::uint32_t any = 0;
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
          std::uint32_t bits;
          std::memcpy(&bits, v + i, 4);
          any |= std::uint32_t((bits & 0x7f800000u) == 0x7f800000u);
        }
        if (!any) return found;
        for (std::size_t i = r.begin(); i != r.end(); ++i)
          if (!std::isfinite(v[i])) return std::min(found, i);
        return found;
      },
      [](std::size_t a, std::size_t b) { return std::min(a, b); });
}

}  // namespace chokeloops::detail
