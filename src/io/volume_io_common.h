#pragma once
// What every volume format's reader and writer share (volume_io.cpp: NIfTI, NRRD; metaimage_io.cpp:
// MetaImage): the one-line error naming the file, the checks of the index-to-world transform and of the
// values, and the typed store of the editors. Internal to src/io; the public entry point is volume_io.h.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <type_traits>
#include <vector>

#include "chokeloops/io/volume_io.h"

namespace chokeloops::volume_detail {

// Whether `s` ends with `lower_tail` (given in lower case), ignoring the case of `s`.
bool ends_with(const std::string& s, const std::string& lower_tail);

// Throws Error(2) "path: what".
[[noreturn]] void fail(const std::string& path, const std::string& what);

// A library's multi-line message as one line (the CLI's error contract).
std::string one_line(std::string s);

// Fills v.spacing from the affine's columns; refuses a zero, non-finite or singular transform, warns when the
// axes are sheared.
void finish_affine(VolumeImage& v);

// Refuses NaN/Inf values, naming the first such voxel.
void check_values(const VolumeImage& v);

// image.values as raw elements of image.datatype ("uint8", "int16", "int32", "float32"), native byte order.
std::vector<std::uint8_t> packed_values(const VolumeImage& image);

// Stores `value` (scaled units) into raw element `i` of type T: the inverse of the reader's scaling,
// rounded and clamped for integer types.
template <class T>
void store(void* data, std::size_t i, double value) {
  if constexpr (std::is_integral_v<T>) {
    const double r = std::round(value);
    const double lo = double(std::numeric_limits<T>::lowest()), hi = double(std::numeric_limits<T>::max());
    static_cast<T*>(data)[i] = T(std::min(hi, std::max(lo, r)));
  } else {
    static_cast<T*>(data)[i] = T(value);
  }
}

}  // namespace chokeloops::volume_detail

// MetaImage (.mha, .mhd + .raw/.zraw) through ITK's MetaIO: metaimage_io.cpp.
namespace chokeloops::metaimage {

bool is_metaimage_path(const std::string& path);
VolumeImage read_metaimage(const std::string& path, int volume);
void write_metaimage_labels(const VolumeImage& like, const std::vector<std::int32_t>& labels, const std::string& path);
void write_metaimage_scalar(const VolumeImage& image, const std::string& path, bool compress);
void write_metaimage_edited(const VolumeImage& like, const std::vector<std::pair<std::int64_t, double>>& changes,
                            const std::string& path);

}  // namespace chokeloops::metaimage
