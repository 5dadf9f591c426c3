// MetaImage (.mha with its voxels inline, .mhd with a .raw/.zraw data file) through ITK's MetaIO, which
// Debian ships inside libinsighttoolkit5-dev as a plain C++ library (README "Medical volumes").
// MetaIO parses the header and writes files. The voxel data is read here, not by MetaIO: the MetaIO of
// ITK 5.2 ignores a short read of the data file and a compressed stream that does not inflate (it returns
// success with part of the buffer unwritten), and allocates what DimSize promises before reading; here the
// data file's size is checked first and the stream must inflate to exactly DimSize x ElementType bytes.
#include <metaImage.h>
#include <zlib.h>

#include <array>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "chokeloops/field/levelset.h"
#include "chokeloops/grid.h"
#include "volume_io_common.h"

namespace chokeloops::metaimage {

using namespace volume_detail;

namespace {

namespace fs = std::filesystem;

// MetaIO reports its problems on std::cout/std::cerr; the CLI promises one line on stderr. What it says while
// one of these is alive is kept (and becomes part of our error when the call fails).
class MetaIOMessages {
 public:
  MetaIOMessages() : out_(std::cout.rdbuf(text_.rdbuf())), err_(std::cerr.rdbuf(text_.rdbuf())) {}
  ~MetaIOMessages() {
    std::cout.rdbuf(out_);
    std::cerr.rdbuf(err_);
  }
  MetaIOMessages(const MetaIOMessages&) = delete;
  MetaIOMessages& operator=(const MetaIOMessages&) = delete;
  std::string text() const {
    const std::string t = one_line(text_.str());
    return t.empty() ? t : " (MetaIO: " + t + ")";
  }

 private:
  std::ostringstream text_;
  std::streambuf* out_;
  std::streambuf* err_;
};

// MetaIO's header, plus the one field it parses but does not hand out.
class MetaHeader : public MetaImage {
 public:
  std::streamoff compressed_data_size() const { return m_CompressedDataSize; }
};

struct ElementKind {
  MET_ValueEnumType type;
  const char* datatype;  // VolumeImage::datatype
  bool integer;
};

// The scalar element types taken (those of NIfTI/NRRD); MET_LONG/ULONG are 32-bit in MetaIO.
constexpr ElementKind kElementKinds[] = {
    {MET_CHAR, "int8", true},     {MET_UCHAR, "uint8", true}, {MET_SHORT, "int16", true},
    {MET_USHORT, "uint16", true}, {MET_INT, "int32", true},   {MET_UINT, "uint32", true},
    {MET_LONG, "int32", true},    {MET_ULONG, "uint32", true}, {MET_FLOAT, "float32", false},
    {MET_DOUBLE, "float64", false}};

bool native_msb() {
  const std::uint16_t one = 1;
  std::uint8_t first;
  std::memcpy(&first, &one, 1);
  return first == 0;
}

std::string type_name(MET_ValueEnumType t) {
  return t >= 0 && t < MET_NUM_VALUE_TYPES ? MET_ValueTypeName[t] : "unknown (" + std::to_string(int(t)) + ")";
}

// A parsed header and where its voxels are; no voxel data.
struct MetaFile {
  std::string path;
  std::shared_ptr<MetaHeader> header;
  int ndims = 0;
  std::array<std::int64_t, 4> size{1, 1, 1, 1};  // DimSize, 1 past NDims
  int channels = 1;                              // ElementNumberOfChannels (interleaved)
  ElementKind kind{};
  int element_bytes = 0;
  std::string data_path;        // the file holding the voxels (path itself when LOCAL)
  std::streamoff data_start = 0;
  std::streamoff stored_bytes = 0;  // bytes at data_start: the raw data, or its compressed stream
  bool compressed = false;
  std::size_t element_count() const { return std::size_t(size[0] * size[1] * size[2] * size[3]) * std::size_t(channels); }
  std::size_t data_bytes() const { return element_count() * std::size_t(element_bytes); }
};

std::string trimmed(std::string s) {
  s.resize(std::strlen(s.c_str()));  // MetaIO compares keys as C strings
  const auto first = s.find_first_not_of(" \t\r\n\f\v");
  if (first == std::string::npos) return "";
  return s.substr(first, s.find_last_not_of(" \t\r\n\f\v") - first + 1);
}

// Guards MetaIO 5.2's header parser, which trusts its input (each found by fuzzing): it reads DimSize,
// ElementSpacing, Offset and TransformMatrix as NDims (NDims^2) numbers before it looks at NDims, so a
// negative NDims loops ~2^64 times and one above 10 writes past its fixed arrays; and it copies field names
// and values such as Comment into 255-byte buffers unchecked. So before MetaIO sees the file, the header's
// lines (up to the ElementDataFile line that ends it) must be shorter than 255 bytes, each must hold a name and a
// value, and NDims, found as MetaIO finds it, must be a plain integer from 1 to 10 on its own line.
// A field name as a one-line message may show it: control and non-ASCII bytes as '?', at most 40 characters.
std::string printable_name(std::string s) {
  if (s.size() > 40) s = s.substr(0, 37) + "...";
  for (auto& c : s)
    if (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126) c = '?';
  return s;
}

void check_header_before_metaio(const std::string& path, std::istream& in) {
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    if (line.size() > 254)
      fail(path, "header line " + std::to_string(number) + " is " + std::to_string(line.size()) +
                     " bytes long: MetaImage header lines must be shorter than 255 bytes");
    // a name ends at '=' or ':', or at the end of the line (MetaIO then takes the value from a later line)
    const auto sep = line.find_first_of("=:\r");
    const std::string key = trimmed(line.substr(0, sep));
    if (key == "ElementDataFile") break;
    const bool no_value = sep == std::string::npos || line[sep] == '\r';
    // A name alone on its line takes the next line as its value in MetaIO, so that line is no field of its own:
    // an ElementDataFile there did not end MetaIO's header, and a negative NDims further down looped ~2^64 times
    // (found by fuzzing, regression-8cc5550860d4). A header line must hold a name and its value.
    if (no_value && key != "NDims" && !key.empty())
      fail(path, "header line " + std::to_string(number) + " ('" + printable_name(key) +
                     "') has no '=' and value: not a readable MetaImage header");
    if (key != "NDims") continue;
    const std::string value = no_value ? "" : trimmed(line.substr(sep + 1));
    char* end = nullptr;
    const long n = std::strtol(value.c_str(), &end, 10);
    if (value.empty() || *end != '\0' || n < 1 || n > 10)
      fail(path, "NDims = " + value.substr(0, 40) + " is not a number of dimensions");
  }
  in.clear();
  in.seekg(0);
}

MetaFile parse(const std::string& path) {
  MetaFile f;
  f.path = path;
  f.header = std::make_shared<MetaHeader>();
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, "cannot open the file");
  check_header_before_metaio(path, in);
  std::streamoff header_end = -1;
  {
    MetaIOMessages messages;
    if (!f.header->ReadStream(0, &in, false))
      fail(path, "not a readable MetaImage header (a required field such as NDims, DimSize, ElementType or "
                 "ElementDataFile is missing or malformed)" + messages.text());
    header_end = in.tellg();
  }
  MetaHeader& h = *f.header;
  f.ndims = h.NDims();
  if (f.ndims < 3 || f.ndims > 4)
    fail(path, "NDims = " + std::to_string(f.ndims) + ": a 3D image is needed (NDims 3, or 4 with --volume K)");
  for (int a = 0; a < f.ndims; ++a) {
    f.size[a] = h.DimSize(a);
    if (f.size[a] < 1 || f.size[a] > (1 << 20))
      fail(path, "DimSize[" + std::to_string(a) + "] = " + std::to_string(f.size[a]) + " is not a valid size");
  }
  f.channels = h.ElementNumberOfChannels();
  if (f.channels < 1 || f.channels > (1 << 16))
    fail(path, "ElementNumberOfChannels = " + std::to_string(f.channels) + " is not a valid count");
  if (f.ndims == 4 && f.channels > 1)
    fail(path, "a 4D image of " + std::to_string(f.channels) +
                   " channels per voxel (ElementNumberOfChannels): images of more than 4 dimensions are not supported");
  const ElementKind* kind = nullptr;
  for (const auto& k : kElementKinds)
    if (k.type == h.ElementType()) kind = &k;
  if (!kind)
    fail(path, "ElementType " + type_name(h.ElementType()) +
                   " is not supported: give a scalar image (8-32 bit integer or float); several components per "
                   "voxel are given by ElementNumberOfChannels");
  f.kind = *kind;
  f.element_bytes = MET_ValueTypeSize[kind->type];
  if (!h.BinaryData())
    fail(path, "BinaryData = False (voxels written as text) is not supported: write the image with binary data");
  f.compressed = h.CompressedData();

  const std::string data_name = h.ElementDataFileName();
  std::string upper = data_name;
  for (auto& c : upper) c = char(std::toupper(static_cast<unsigned char>(c)));
  if (upper == "LOCAL") {
    if (header_end < 0) fail(path, "ElementDataFile = LOCAL but the file ends with its header");
    f.data_path = path;
    f.data_start = header_end;
  } else if (upper.rfind("LIST", 0) == 0 || data_name.find('%') != std::string::npos) {
    fail(path, "ElementDataFile = " + data_name +
                   ": images stored as one file per slice are not supported; save the image as one .mha");
  } else {
    const fs::path named(data_name);
    f.data_path = (named.is_absolute() ? named : fs::path(path).parent_path() / named).string();
    std::error_code ec;
    // MetaIO's own fallback: a data file gzipped after the header was written.
    if (!fs::exists(f.data_path, ec) && fs::exists(f.data_path + ".gz", ec)) {
      f.data_path += ".gz";
      f.compressed = true;
    }
  }
  std::error_code ec;
  const std::uintmax_t file_bytes = fs::is_regular_file(f.data_path, ec) ? fs::file_size(f.data_path, ec) : 0;
  if (!fs::is_regular_file(f.data_path, ec) || ec)
    fail(path, "ElementDataFile " + data_name + ": cannot open the voxel data file " + f.data_path);
  // DimSize values are at most 2^20 each: the product is taken in long double so that it cannot wrap.
  const long double promised = (long double)f.size[0] * f.size[1] * f.size[2] * f.size[3] * f.channels * f.element_bytes;
  const int header_size = h.HeaderSize();
  if (header_size > 0) f.data_start = header_size;  // bytes skipped at the start of the data file (MetaIO's meaning)
  if (header_size < -1) fail(path, "HeaderSize = " + std::to_string(header_size) + " is not a valid size");
  if (header_size == -1) {  // the data is the file's last bytes
    if (f.compressed) fail(path, "HeaderSize = -1 (data at the end of the file) cannot be used with CompressedData = True");
    if (promised > (long double)file_bytes)
      fail(path, "the voxel data is shorter than DimSize x ElementType promise (" + std::to_string(std::uintmax_t(promised)) +
                     " bytes; " + f.data_path + " has " + std::to_string(file_bytes) + ")");
    f.data_start = std::streamoff(file_bytes - std::uintmax_t(promised));
  }
  if ((std::uintmax_t)f.data_start > file_bytes)
    fail(path, "the voxel data would start at byte " + std::to_string(f.data_start) + ", past the end of " + f.data_path);
  const std::uintmax_t available = file_bytes - std::uintmax_t(f.data_start);
  if (f.compressed) {
    const std::streamoff declared = h.compressed_data_size();
    if (declared < 0 || std::uintmax_t(declared) > available)
      fail(path, "CompressedDataSize = " + std::to_string(declared) + " is more than the " + std::to_string(available) +
                     " bytes of compressed voxel data in " + f.data_path);
    f.stored_bytes = declared > 0 ? declared : std::streamoff(available);
    // deflate shrinks data at most 1032-fold: a stream this short cannot hold what DimSize promises
    if (promised > (long double)f.stored_bytes * 1032)
      fail(path, "the compressed voxel data (" + std::to_string(f.stored_bytes) + " bytes) cannot hold what DimSize x " +
                     "ElementType promise (" + std::to_string(std::uintmax_t(promised)) + " bytes)");
  } else {
    if (promised > (long double)available)
      fail(path, "the voxel data is shorter than DimSize x ElementType promise (" + std::to_string(std::uintmax_t(promised)) +
                     " bytes; " + f.data_path + " has " + std::to_string(available) + " from byte " +
                     std::to_string(f.data_start) + ")");
    f.stored_bytes = std::streamoff(promised);
  }
  return f;
}

// Inflates a zlib or gzip stream into exactly out.size() bytes; false (with zlib's reason) when the stream is
// corrupt, ends early or holds more.
bool inflate_exactly(std::vector<std::uint8_t>& in, std::vector<std::uint8_t>& out, std::string& why) {
  z_stream s{};
  if (inflateInit2(&s, 15 + 32) != Z_OK) {  // 15 + 32: zlib or gzip header, detected
    why = "zlib cannot start";
    return false;
  }
  constexpr std::size_t kChunk = std::size_t(1) << 30;  // avail_in/avail_out are 32-bit
  std::size_t in_pos = 0, out_pos = 0;
  std::uint8_t past_end = 0;  // one byte beyond the promised data: the stream must not need it
  int rc = Z_OK;
  for (;;) {
    if (s.avail_in == 0 && in_pos < in.size()) {
      const std::size_t n = std::min(kChunk, in.size() - in_pos);
      s.next_in = in.data() + in_pos;
      s.avail_in = uInt(n);
      in_pos += n;
    }
    if (s.avail_out == 0) {
      if (out_pos < out.size()) {
        const std::size_t n = std::min(kChunk, out.size() - out_pos);
        s.next_out = out.data() + out_pos;
        s.avail_out = uInt(n);
        out_pos += n;
      } else if (s.next_out != &past_end + 1) {
        s.next_out = &past_end;
        s.avail_out = 1;
      }
    }
    rc = inflate(&s, Z_NO_FLUSH);
    if (rc == Z_STREAM_END) break;
    if (s.next_out == &past_end + 1) {
      why = "it holds more than DimSize x ElementType bytes";
      break;
    }
    if (rc == Z_BUF_ERROR && s.avail_in == 0 && in_pos == in.size()) {
      why = "the stream ends early";
      break;
    }
    if (rc != Z_OK && rc != Z_BUF_ERROR) {
      why = s.msg ? s.msg : "corrupt stream";
      break;
    }
  }
  const bool ok = rc == Z_STREAM_END && s.total_out == out.size();
  if (rc == Z_STREAM_END && !ok) why = "it inflates to " + std::to_string(s.total_out) + " bytes";
  inflateEnd(&s);
  return ok;
}

// Every element of the file (all volumes and channels), in native byte order.
std::vector<std::uint8_t> load_elements(const MetaFile& f) {
  const std::size_t bytes = f.data_bytes();
  if (bytes + std::size_t(f.compressed ? f.stored_bytes : 0) > default_max_memory())
    throw Error(f.path + ": the image needs " + std::to_string(bytes >> 20) + " MiB, more than the memory allowed", 3);
  std::ifstream in(f.data_path, std::ios::binary);
  in.seekg(f.data_start);
  std::vector<std::uint8_t> stored(std::size_t(f.stored_bytes));
  in.read(reinterpret_cast<char*>(stored.data()), std::streamsize(stored.size()));
  if (!in || std::size_t(in.gcount()) != stored.size())
    fail(f.path, "cannot read the voxel data of " + f.data_path + " (" + std::to_string(stored.size()) + " bytes from byte " +
                     std::to_string(f.data_start) + ")");
  std::vector<std::uint8_t> raw;
  if (f.compressed) {
    raw.resize(bytes);
    std::string why;
    if (!inflate_exactly(stored, raw, why))
      fail(f.path, "the compressed voxel data (CompressedData = True) does not inflate to DimSize x ElementType (" +
                       std::to_string(bytes) + " bytes): " + why);
  } else {
    raw = std::move(stored);
  }
  if (f.header->BinaryDataByteOrderMSB() != native_msb() && f.element_bytes > 1)
    for (std::size_t i = 0; i < bytes; i += std::size_t(f.element_bytes))
      std::reverse(raw.begin() + std::ptrdiff_t(i), raw.begin() + std::ptrdiff_t(i + std::size_t(f.element_bytes)));
  return raw;
}

template <class Fn>
void with_element_type(MET_ValueEnumType t, Fn&& fn) {
  switch (t) {
    case MET_CHAR: fn(std::int8_t{}); break;
    case MET_UCHAR: fn(std::uint8_t{}); break;
    case MET_SHORT: fn(std::int16_t{}); break;
    case MET_USHORT: fn(std::uint16_t{}); break;
    case MET_INT: case MET_LONG: fn(std::int32_t{}); break;
    case MET_UINT: case MET_ULONG: fn(std::uint32_t{}); break;
    case MET_FLOAT: fn(float{}); break;
    case MET_DOUBLE: fn(double{}); break;
    default: throw std::logic_error("MetaImage element type " + type_name(t));
  }
}

// The element of voxel i of volume `volume`: a 4th dimension is the slowest axis, channels interleave.
std::size_t element_index(const MetaFile& f, std::size_t voxels, std::size_t i, int volume) {
  return f.ndims == 4 ? std::size_t(volume) * voxels + i : i * std::size_t(f.channels) + std::size_t(volume);
}

// ITK's AnatomicalOrientation letters for the direction of each axis in LPS ("RAI": +x, +y, +z, i.e. from
// right to left, anterior to posterior, inferior to superior).
std::string orientation_of(const std::array<std::array<double, 4>, 3>& affine) {
  std::string code;
  for (int c = 0; c < 3; ++c) {
    int r = 0;
    for (int q = 1; q < 3; ++q)
      if (std::abs(affine[q][c]) > std::abs(affine[r][c])) r = q;
    const bool plus = affine[r][c] > 0;
    code += r == 0 ? (plus ? 'R' : 'L') : r == 1 ? (plus ? 'A' : 'P') : (plus ? 'I' : 'S');
  }
  return code;
}

// A MetaImage for `dims` and an LPS `affine`: ElementSpacing = column norms, TransformMatrix = the unit
// columns (stored axis by axis, as ITK reads it), Offset = the origin.
void set_grid(MetaImage& m, const std::array<std::array<double, 4>, 3>& affine) {
  double matrix[9], offset[3];
  for (int c = 0; c < 3; ++c) {
    const double norm = std::sqrt(affine[0][c] * affine[0][c] + affine[1][c] * affine[1][c] + affine[2][c] * affine[2][c]);
    m.ElementSpacing(c, norm);
    for (int r = 0; r < 3; ++r) matrix[c * 3 + r] = affine[r][c] / norm;
    offset[c] = affine[c][3];
  }
  m.TransformMatrix(matrix);
  m.Offset(offset);
  m.AnatomicalOrientation(orientation_of(affine).c_str());
}

void write(MetaImage& m, const std::string& path) {
  MetaIOMessages messages;
  m.BinaryData(true);
  m.BinaryDataByteOrderMSB(native_msb());
  // .mha: voxels inline; .mhd: MetaIO names the data file <stem>.raw (.zraw when compressed) beside it.
  const bool ok = m.Write(path.c_str(), ends_with(path, ".mha") ? "LOCAL" : nullptr);
  std::error_code ec;
  if (!ok || !fs::is_regular_file(path, ec)) throw Error("cannot write " + path + messages.text(), 3);
}

void write_grid(const std::array<int, 3>& dims, const std::array<std::array<double, 4>, 3>& affine,
                MET_ValueEnumType type, const void* data, bool compress, const std::string& path,
                const MetaImage* like) {
  const double ones[3] = {1, 1, 1};
  MetaImage m(3, dims.data(), ones, type, 1, const_cast<void*>(data));
  m.AutoFreeElementData(false);
  set_grid(m, affine);
  if (like) m.DistanceUnits(like->DistanceUnits());
  m.CompressedData(compress);
  write(m, path);
}

}  // namespace

bool is_metaimage_path(const std::string& path) { return ends_with(path, ".mha") || ends_with(path, ".mhd"); }

VolumeImage read_metaimage(const std::string& path, int volume) {
  const MetaFile f = parse(path);
  const MetaHeader& h = *f.header;
  VolumeImage v;
  v.path = path;
  v.format = "metaimage";
  v.dims = {int(f.size[0]), int(f.size[1]), int(f.size[2])};
  if (v.dims[0] < 2 || v.dims[1] < 2 || v.dims[2] < 2)
    fail(path, "DimSize " + std::to_string(v.dims[0]) + " " + std::to_string(v.dims[1]) + " " + std::to_string(v.dims[2]) +
                   ": a 3D image needs at least 2 voxels along each axis");
  const std::string volume_field = f.ndims == 4 ? "DimSize[3]" : "ElementNumberOfChannels";
  v.volumes = int(f.ndims == 4 ? f.size[3] : f.channels);
  if (v.volumes > 1 && volume < 0)
    fail(path, "a 4D image of " + std::to_string(v.volumes) + " volumes (" + volume_field + "); choose one with --volume K (0.." +
                   std::to_string(v.volumes - 1) + ")");
  if (volume >= v.volumes)
    fail(path, "--volume " + std::to_string(volume) + " is past the image's " + std::to_string(v.volumes) + " volume(s)");
  v.volume = std::max(volume, 0);
  v.datatype = f.kind.datatype;
  v.integer_type = f.kind.integer;

  const std::vector<std::uint8_t> raw = load_elements(f);
  const std::size_t voxels = std::size_t(v.voxel_count());
  v.values.resize(voxels);
  with_element_type(f.kind.type, [&](auto tag) {
    using T = decltype(tag);
    for (std::size_t i = 0; i < voxels; ++i) {
      T x;
      std::memcpy(&x, &raw[element_index(f, voxels, i, v.volume) * sizeof(T)], sizeof(T));
      v.values[i] = float(x);
    }
  });
  check_values(v);
  // ITK, and so Slicer and ITK-SNAP, read the stored values: the intensity function is not applied here either.
  if (h.ElementToIntensityFunctionSlope() != 1 || h.ElementToIntensityFunctionOffset() != 0)
    v.warnings.push_back("ElementToIntensityFunctionSlope/Offset are not applied (as in ITK): values are the stored ones");

  // World: ITK's LPS mm. TransformMatrix holds the direction of axis c as its c-th group of NDims numbers.
  const double* matrix = h.TransformMatrix();
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) v.affine[r][c] = matrix[c * f.ndims + r] * h.ElementSpacing(c);
  for (int r = 0; r < 3; ++r) v.affine[r][3] = h.Offset(r);
  v.convention = "LPS";
  v.transform_source = "TransformMatrix/Offset";
  finish_affine(v);
  std::string declared = h.AnatomicalOrientationAcronym();
  declared.resize(std::min<std::size_t>(declared.size(), 3));
  const std::string actual = orientation_of(v.affine);
  if (declared.find('?') == std::string::npos && declared.size() == 3 && declared != actual)
    v.warnings.push_back("AnatomicalOrientation " + declared + " disagrees with TransformMatrix (" + actual +
                         "); positions follow TransformMatrix, as in ITK");
  if (h.DistanceUnits() != MET_DISTANCE_UNITS_UNKNOWN && h.DistanceUnits() != MET_DISTANCE_UNITS_MM)
    v.warnings.push_back(std::string("DistanceUnits = ") + h.DistanceUnitsName() +
                         ", not mm: positions and lengths are in those units");
  v.header = std::static_pointer_cast<void>(f.header);
  return v;
}

void write_metaimage_labels(const VolumeImage& like, const std::vector<std::int32_t>& labels, const std::string& path) {
  // On the input's grid (its 3D affine, so a 4D input's labels are 3D) and always compressed: labels are mostly 0.
  write_grid(like.dims, like.affine, MET_INT, labels.data(), true, path, static_cast<const MetaHeader*>(like.header.get()));
}

void write_metaimage_scalar(const VolumeImage& image, const std::string& path, bool compress) {
  const std::vector<std::uint8_t> bytes = packed_values(image);
  const MET_ValueEnumType type = image.datatype == "uint8" ? MET_UCHAR
                                 : image.datatype == "int16" ? MET_SHORT
                                 : image.datatype == "int32" ? MET_INT
                                                             : MET_FLOAT;
  auto lps = image.affine;
  if (image.convention == "RAS")
    for (int c = 0; c < 4; ++c) lps[0][c] = -lps[0][c], lps[1][c] = -lps[1][c];
  write_grid(image.dims, lps, type, bytes.data(), compress, path, nullptr);
}

void write_metaimage_edited(const VolumeImage& like, const std::vector<std::pair<std::int64_t, double>>& changes,
                            const std::string& path) {
  if (!is_metaimage_path(path))
    throw Error(path + ": the input is MetaImage; write the filtered image as .mha (or .mhd with a .raw beside it)");
  const MetaFile f = parse(like.path);
  std::vector<std::uint8_t> raw = load_elements(f);
  const std::size_t voxels = std::size_t(like.voxel_count());
  with_element_type(f.kind.type, [&](auto tag) {
    using T = decltype(tag);
    for (const auto& [i, value] : changes) store<T>(raw.data(), element_index(f, voxels, std::size_t(i), like.volume), value);
  });
  // The input's header as MetaIO read it (spacing, TransformMatrix, Offset, units, modality, its own extra
  // fields), its element type and compression; the data in native byte order.
  MetaHeader& h = *f.header;
  int size[4];
  for (int a = 0; a < f.ndims; ++a) size[a] = int(f.size[a]);
  MetaImage out(f.ndims, size, h.ElementSpacing(), f.kind.type, f.channels, raw.data());
  out.AutoFreeElementData(false);
  out.CopyInfo(&h);
  out.HeaderSize(0);
  out.AnatomicalOrientation(h.AnatomicalOrientation());
  out.CompressedData(f.compressed);
  if (h.ElementMinMaxValid()) out.ElementMinMaxRecalc();
  for (int i = 0; i < h.GetNumberOfAdditionalReadFields(); ++i)
    out.AddUserField(h.GetAdditionalReadFieldName(i), MET_STRING, int(std::strlen(h.GetAdditionalReadFieldValue(i))),
                     h.GetAdditionalReadFieldValue(i), true, -1);
  write(out, path);
}

}  // namespace chokeloops::metaimage
