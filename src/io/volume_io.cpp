// NIfTI-1/2 through niftilib's nifti2_io (reads both versions, .gz included), NRRD through teem's nrrd.
// Both libraries are Debian packages (libnifti2-dev, libteem-dev); see README "Medical volumes" for why not
// all of ITK. MetaImage is in metaimage_io.cpp; this file dispatches to it.
#include "chokeloops/io/volume_io.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <nifti/nifti2_io.h>
#include <teem/nrrd.h>

#include "chokeloops/field/levelset.h"
#include "chokeloops/grid.h"
#include "common/first_non_finite.h"
#include "volume_io_common.h"

namespace chokeloops {

namespace volume_detail {

bool ends_with(const std::string& s, const std::string& tail) {
  if (s.size() < tail.size()) return false;
  return std::equal(tail.rbegin(), tail.rend(), s.rbegin(), [](char a, char b) { return std::tolower(a) == b; });
}

[[noreturn]] void fail(const std::string& path, const std::string& what) { throw Error(path + ": " + what); }

std::string one_line(std::string s) {
  for (auto& c : s)
    if (c == '\n' || c == '\r') c = ' ';
  while (!s.empty() && s.back() == ' ') s.pop_back();
  return s;
}

// Column norms of the 3x3 part; a zero or non-finite column is a broken transform.
void finish_affine(VolumeImage& v) {
  for (int c = 0; c < 3; ++c) {
    double n = 0;
    for (int r = 0; r < 3; ++r) n += v.affine[r][c] * v.affine[r][c];
    n = std::sqrt(n);
    if (!(n > 0) || !std::isfinite(n))
      fail(v.path, "the index-to-world transform (" + v.transform_source + ") has a zero or invalid column " +
                       std::to_string(c) + "; the voxel spacing is unknown");
    v.spacing[c] = n;
  }
  for (int r = 0; r < 3; ++r)
    if (!std::isfinite(v.affine[r][3])) fail(v.path, "the image origin (" + v.transform_source + ") is not finite");
  // Distances are exact only when the axes are orthogonal (no shear); say so when they are not.
  double worst = 0;
  for (int a = 0; a < 3; ++a)
    for (int b = a + 1; b < 3; ++b) {
      double d = 0;
      for (int r = 0; r < 3; ++r) d += v.affine[r][a] * v.affine[r][b];
      worst = std::max(worst, std::abs(d) / (v.spacing[a] * v.spacing[b]));
    }
  if (worst > 1e-3)
    v.warnings.push_back("the image axes are not orthogonal (sheared transform, cosine " + std::to_string(worst) +
                         "): distances are measured along the voxel axes, positions are exact");
  // Axes that are (nearly) linearly dependent map distinct voxels to one world point: no position is meaningful.
  const auto& m = v.affine;
  const double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                     m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  if (!(std::abs(det) > 1e-6 * v.spacing[0] * v.spacing[1] * v.spacing[2]))
    fail(v.path, "the index-to-world transform (" + v.transform_source +
                     ") is singular: its axes are linearly dependent");
}

void check_values(const VolumeImage& v) {
  const std::size_t i = detail::first_non_finite(v.values.data(), v.values.size());
  if (i == v.values.size()) return;
  const std::size_t nx = std::size_t(v.dims[0]), ny = std::size_t(v.dims[1]);
  fail(v.path, std::string("voxel (") + std::to_string(i % nx) + "," + std::to_string(i / nx % ny) + "," +
                   std::to_string(i / (nx * ny)) + ") is " + (std::isnan(v.values[i]) ? "NaN" : "infinite") +
                   "; the image must hold finite values");
}

std::vector<std::uint8_t> packed_values(const VolumeImage& image) {
  const std::size_t n = std::size_t(image.voxel_count());
  if (image.values.size() != n) throw std::logic_error("packed_values: values do not match dims");
  std::vector<std::uint8_t> bytes;
  auto pack = [&](auto tag) {
    using T = decltype(tag);
    bytes.resize(n * sizeof(T));
    for (std::size_t i = 0; i < n; ++i) {
      T v = T(image.values[i]);
      std::memcpy(&bytes[i * sizeof(T)], &v, sizeof(T));
    }
  };
  if (image.datatype == "uint8") pack(std::uint8_t{});
  else if (image.datatype == "int16") pack(std::int16_t{});
  else if (image.datatype == "int32") pack(std::int32_t{});
  else if (image.datatype == "float32") pack(float{});
  else throw std::logic_error("write_scalar_volume: datatype " + image.datatype);
  return bytes;
}

}  // namespace volume_detail

using namespace volume_detail;

namespace {

bool is_nifti(const std::string& p) {
  return ends_with(p, ".nii") || ends_with(p, ".nii.gz") || ends_with(p, ".hdr") || ends_with(p, ".img") ||
         ends_with(p, ".hdr.gz") || ends_with(p, ".img.gz");
}
bool is_nrrd(const std::string& p) { return ends_with(p, ".nrrd") || ends_with(p, ".nhdr"); }

VolumeImage read_nifti(const std::string& path, int volume) {
  nifti_set_debug_level(0);  // the library's own messages would break the one-line error
  VolumeImage v;
  v.path = path;
  std::shared_ptr<nifti_image> hdr(nifti_image_read(path.c_str(), 0), [](nifti_image* p) { if (p) nifti_image_free(p); });
  if (!hdr) fail(path, "not a readable NIfTI-1/2 header (missing, truncated or not NIfTI)");
  v.format = hdr->nifti_type >= 4 ? "nifti2" : "nifti1";
  for (int a = 1; a <= 3; ++a)
    if (hdr->dim[a] < 1 || hdr->dim[a] > (1 << 20)) fail(path, "dim[" + std::to_string(a) + "] = " + std::to_string(hdr->dim[a]) + " is not a valid size");
  for (int a = 5; a <= 7 && a <= hdr->dim[0]; ++a)
    if (hdr->dim[a] > 1) fail(path, "dim[" + std::to_string(a) + "] = " + std::to_string(hdr->dim[a]) + ": images of more than 4 dimensions are not supported");
  v.dims = {int(hdr->nx), int(hdr->ny), int(hdr->nz)};
  if (v.dims[0] < 2 || v.dims[1] < 2 || v.dims[2] < 2)
    fail(path, "dims " + std::to_string(v.dims[0]) + "x" + std::to_string(v.dims[1]) + "x" + std::to_string(v.dims[2]) +
                   ": a 3D image needs at least 2 voxels along each axis");
  v.volumes = hdr->dim[0] >= 4 ? int(std::max<std::int64_t>(1, hdr->nt)) : 1;
  if (v.volumes > 1 && volume < 0)
    fail(path, "a 4D image of " + std::to_string(v.volumes) + " volumes (dim[4]); choose one with --volume K (0.." +
                   std::to_string(v.volumes - 1) + ")");
  if (volume >= v.volumes) fail(path, "--volume " + std::to_string(volume) + " is past the image's " + std::to_string(v.volumes) + " volume(s)");
  v.volume = std::max(volume, 0);

  int dt = hdr->datatype;
  switch (dt) {
    case DT_UINT8: v.datatype = "uint8"; break;
    case DT_INT8: v.datatype = "int8"; break;
    case DT_INT16: v.datatype = "int16"; break;
    case DT_UINT16: v.datatype = "uint16"; break;
    case DT_INT32: v.datatype = "int32"; break;
    case DT_UINT32: v.datatype = "uint32"; break;
    case DT_FLOAT32: v.datatype = "float32"; break;
    case DT_FLOAT64: v.datatype = "float64"; break;
    default:
      fail(path, std::string("datatype ") + std::to_string(dt) + " (" + nifti_datatype_string(dt) +
                     ") is not supported: give a scalar image (integer or float)");
  }
  v.integer_type = dt != DT_FLOAT32 && dt != DT_FLOAT64;
  // The data, read through znzlib (nifti's own zlib layer) rather than nifti_image_read: niftilib quietly
  // replaces NaN/Inf floats by 0, and a NaN must be refused, not analysed as 0. Only volume K is read.
  const std::size_t n3 = std::size_t(v.voxel_count());
  const std::size_t bytes = n3 * std::size_t(hdr->nbyper);
  // Guard before allocating (found by fuzzing): a header may promise far more data than the file holds.
  // A gzip stream inflates at most 1032-fold, so a compressed file bounds the data it can hold as well.
  // The offset must be a position in the file and the data file must exist to bound it (found by fuzzing: a
  // vox_offset of NaN becomes the offset -2^31, which made the data "fit" in a 350-byte file, and
  // 1286x256x1024 floats were allocated before the read failed).
  {
    if (!hdr->iname) fail(path, "the header names no voxel data file");
    if (hdr->iname_offset < 0)
      fail(path, "the voxel data offset (vox_offset) is negative or not a number (" +
                     std::to_string(hdr->iname_offset) + ")");
    std::error_code ec;
    const std::uintmax_t file_bytes = std::filesystem::file_size(hdr->iname, ec);
    if (ec) fail(path, std::string("cannot open the voxel data file ") + hdr->iname + " (" + ec.message() + ")");
    const long double need = (long double)hdr->iname_offset + (long double)bytes * (v.volume + 1);
    const long double can_hold = (long double)file_bytes * (nifti_is_gzfile(hdr->iname) ? 1032 : 1);
    if (need > can_hold)
      fail(path, "the voxel data is shorter than dims x datatype promise (" + std::to_string(bytes) +
                     " bytes per volume; the file has " + std::to_string(file_bytes) + ")");
    if (bytes > default_max_memory())
      throw Error(path + ": one volume needs " + std::to_string(bytes >> 20) + " MiB, more than the memory allowed", 3);
  }
  std::vector<std::uint8_t> raw(bytes);
  {
    znzFile f = znzopen(hdr->iname, "rb", nifti_is_gzfile(hdr->iname));
    if (znz_isnull(f)) fail(path, std::string("cannot open the voxel data file ") + hdr->iname);
    const long long skip = (long long)hdr->iname_offset + (long long)bytes * v.volume;
    const bool ok = znzseek(f, skip, SEEK_SET) >= 0 && znzread(raw.data(), 1, bytes, f) == bytes;
    znzclose(f);
    if (!ok)
      fail(path, "the voxel data is shorter than dims x datatype promise (" + std::to_string(bytes) +
                     " bytes at offset " + std::to_string(skip) + "): file truncated or compressed stream corrupt");
  }
  if (hdr->byteorder != nifti_short_order() && hdr->nbyper > 1)
    nifti_swap_Nbytes(std::int64_t(n3), hdr->nbyper, raw.data());
  v.values.resize(n3);
  const double slope = hdr->scl_slope, inter = hdr->scl_inter;
  const bool scale = slope != 0 && std::isfinite(slope) && std::isfinite(inter) && !(slope == 1 && inter == 0);
  auto convert = [&](auto tag) {
    using T = decltype(tag);
    for (std::size_t i = 0; i < n3; ++i) {
      T x;
      std::memcpy(&x, &raw[i * sizeof(T)], sizeof(T));
      v.values[i] = float(scale ? double(x) * slope + inter : double(x));
    }
  };
  switch (dt) {
    case DT_UINT8: convert(std::uint8_t{}); break;
    case DT_INT8: convert(std::int8_t{}); break;
    case DT_INT16: convert(std::int16_t{}); break;
    case DT_UINT16: convert(std::uint16_t{}); break;
    case DT_INT32: convert(std::int32_t{}); break;
    case DT_UINT32: convert(std::uint32_t{}); break;
    case DT_FLOAT32: convert(float{}); break;
    case DT_FLOAT64: convert(double{}); break;
  }
  std::vector<std::uint8_t>().swap(raw);
  if (scale) v.integer_type = false;
  check_values(v);

  // NIfTI's world is RAS+ mm. sform first (what Slicer and ITK-SNAP show when it is set), then qform.
  const nifti_dmat44* m = nullptr;
  if (hdr->sform_code > 0) { m = &hdr->sto_xyz; v.transform_source = "sform"; }
  else if (hdr->qform_code > 0) { m = &hdr->qto_xyz; v.transform_source = "qform"; }
  if (m) {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) v.affine[r][c] = m->m[r][c];
  } else {
    v.transform_source = "pixdim";
    v.warnings.push_back("no sform or qform: positions are pixdim-scaled voxel indices (NIfTI method 1)");
    const double d[3] = {hdr->dx, hdr->dy, hdr->dz};
    for (int r = 0; r < 3; ++r) v.affine[r][r] = d[r] > 0 ? d[r] : 1.0;
  }
  v.convention = "RAS";
  if (hdr->xyz_units == NIFTI_UNITS_METER || hdr->xyz_units == NIFTI_UNITS_MICRON)
    v.warnings.push_back(std::string("spatial units are ") + nifti_units_string(hdr->xyz_units) +
                         ", not mm: positions and lengths are in those units");
  finish_affine(v);
  v.header = std::static_pointer_cast<void>(hdr);
  return v;
}

std::string biff_message() {
  char* err = biffGetDone(NRRD);
  std::string s = err ? err : "";
  free(err);
  return one_line(s);
}

VolumeImage read_nrrd(const std::string& path, int volume) {
  VolumeImage v;
  v.path = path;
  v.format = "nrrd";
  std::shared_ptr<Nrrd> n(nrrdNew(), [](Nrrd* p) { nrrdNuke(p); });
  if (nrrdLoad(n.get(), path.c_str(), nullptr)) fail(path, "not a readable NRRD: " + biff_message());
  // Spatial axes are those with a space direction; a 4th non-spatial axis must be the slowest.
  std::vector<unsigned> spatial;
  int extra = -1;
  for (unsigned a = 0; a < n->dim; ++a) {
    if (n->spaceDim > 0 && !std::isnan(n->axis[a].spaceDirection[0])) spatial.push_back(a);
    else if (n->spaceDim == 0 && a < 3) spatial.push_back(a);
    else if (extra < 0) extra = int(a);
    else fail(path, "more than one non-spatial axis: images of more than 4 dimensions are not supported");
  }
  if (spatial.size() != 3) fail(path, "dimension " + std::to_string(n->dim) + " with " + std::to_string(spatial.size()) + " spatial axes: a 3D image is needed");
  if (extra >= 0 && extra != 3) fail(path, "the non-spatial axis is axis " + std::to_string(extra) + "; only a slowest 4th axis (volumes) is supported");
  for (int a = 0; a < 3; ++a) v.dims[a] = int(n->axis[a].size);
  if (v.dims[0] < 2 || v.dims[1] < 2 || v.dims[2] < 2)
    fail(path, "sizes " + std::to_string(v.dims[0]) + " " + std::to_string(v.dims[1]) + " " + std::to_string(v.dims[2]) + ": a 3D image needs at least 2 voxels along each axis");
  v.volumes = extra >= 0 ? int(n->axis[3].size) : 1;
  if (v.volumes > 1 && volume < 0)
    fail(path, "a 4D image of " + std::to_string(v.volumes) + " volumes (axis 3); choose one with --volume K (0.." + std::to_string(v.volumes - 1) + ")");
  if (volume >= v.volumes) fail(path, "--volume " + std::to_string(volume) + " is past the image's " + std::to_string(v.volumes) + " volume(s)");
  v.volume = std::max(volume, 0);
  switch (n->type) {
    case nrrdTypeChar: v.datatype = "int8"; break;
    case nrrdTypeUChar: v.datatype = "uint8"; break;
    case nrrdTypeShort: v.datatype = "int16"; break;
    case nrrdTypeUShort: v.datatype = "uint16"; break;
    case nrrdTypeInt: v.datatype = "int32"; break;
    case nrrdTypeUInt: v.datatype = "uint32"; break;
    case nrrdTypeFloat: v.datatype = "float32"; break;
    case nrrdTypeDouble: v.datatype = "float64"; break;
    default: fail(path, std::string("type ") + airEnumStr(nrrdType, n->type) + " is not supported: give a scalar image (8-32 bit integer or float)");
  }
  v.integer_type = n->type != nrrdTypeFloat && n->type != nrrdTypeDouble;
  const std::size_t n3 = std::size_t(v.voxel_count()), off = n3 * std::size_t(v.volume);
  v.values.resize(n3);
  auto lookup = nrrdDLookup[n->type];
  for (std::size_t i = 0; i < n3; ++i) v.values[i] = float(lookup(n->data, off + i));
  check_values(v);
  if (n->spaceDim == 3) {
    for (int a = 0; a < 3; ++a)
      for (int r = 0; r < 3; ++r) v.affine[r][a] = n->axis[a].spaceDirection[r];
    for (int r = 0; r < 3; ++r) v.affine[r][3] = std::isnan(n->spaceOrigin[r]) ? 0.0 : n->spaceOrigin[r];
    v.transform_source = "space directions";
    switch (n->space) {
      case nrrdSpaceRightAnteriorSuperior: case nrrdSpaceRightAnteriorSuperiorTime: v.convention = "RAS"; break;
      case nrrdSpaceLeftAnteriorSuperior: case nrrdSpaceLeftAnteriorSuperiorTime: v.convention = "LAS"; break;
      case nrrdSpaceLeftPosteriorSuperior: case nrrdSpaceLeftPosteriorSuperiorTime: v.convention = "LPS"; break;
      default: v.convention = "scanner"; break;
    }
  } else {
    v.transform_source = "spacings";
    v.convention = "index";
    for (int a = 0; a < 3; ++a) {
      double s = n->axis[a].spacing;
      v.affine[a][a] = std::isfinite(s) && s > 0 ? s : 1.0;
    }
    v.warnings.push_back("no space directions: positions are spacing-scaled voxel indices");
  }
  finish_affine(v);
  v.header = std::static_pointer_cast<void>(n);
  return v;
}

}  // namespace

bool is_volume_path(const std::string& path) {
  return is_nifti(path) || is_nrrd(path) || metaimage::is_metaimage_path(path);
}

VolumeImage read_volume(const std::string& path, int volume) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) fail(path, "no such file");
  if (is_nifti(path)) return read_nifti(path, volume);
  if (is_nrrd(path)) return read_nrrd(path, volume);
  if (metaimage::is_metaimage_path(path)) return metaimage::read_metaimage(path, volume);
  fail(path, "not a volume this program reads (.nii, .nii.gz, .hdr/.img, .nrrd, .nhdr, .mha, .mhd)");
}

namespace {
// Writes a made-up Nrrd gzip-compressed (the outputs are label maps: mostly zeros).
void save_nrrd_gzip(const Nrrd* nrrd, const std::string& path) {
  NrrdIoState* io = nrrdIoStateNew();
  nrrdIoStateEncodingSet(io, nrrdEncodingGzip);
  const int bad = nrrdSave(path.c_str(), nrrd, io);
  nrrdIoStateNix(io);
  if (bad) throw Error("cannot write " + path + ": " + biff_message(), 3);
}
}  // namespace

std::string label_volume_name(const VolumeImage& like, const std::string& stem) {
  if (like.format == "metaimage") return stem + ".mha";
  return stem + (like.format == "nrrd" ? ".nrrd" : ".nii.gz");
}

void write_label_volume(const VolumeImage& like, const std::vector<std::int32_t>& labels, const std::string& path) {
  if (std::int64_t(labels.size()) != like.voxel_count()) throw std::logic_error("label volume size differs from the image's");
  if (!like.header) {  // an image made in memory (tests, benchmarks): its dims and affine make the header
    VolumeImage v;
    v.dims = like.dims;
    v.affine = like.affine;
    v.convention = like.convention;
    v.datatype = "int32";
    v.values.assign(labels.begin(), labels.end());
    write_scalar_volume(v, path);
    return;
  }
  if (like.format == "metaimage") {
    metaimage::write_metaimage_labels(like, labels, path);
    return;
  }
  if (like.format == "nrrd") {
    const Nrrd* in = static_cast<const Nrrd*>(like.header.get());
    std::shared_ptr<Nrrd> out(nrrdNew(), [](Nrrd* p) { nrrdNix(p); });  // nix: the data is ours
    std::size_t size[3] = {std::size_t(like.dims[0]), std::size_t(like.dims[1]), std::size_t(like.dims[2])};
    if (nrrdWrap_nva(out.get(), const_cast<std::int32_t*>(labels.data()), nrrdTypeInt, 3, size) ||
        nrrdSpaceSet(out.get(), in->space) ||
        (in->spaceDim > 0 && nrrdSpaceOriginSet(out.get(), const_cast<double*>(in->spaceOrigin))))
      throw Error("cannot make " + path + ": " + biff_message(), 3);
    for (int a = 0; a < 3; ++a) {
      for (unsigned r = 0; r < in->spaceDim; ++r) out->axis[a].spaceDirection[r] = in->axis[a].spaceDirection[r];
      out->axis[a].spacing = in->axis[a].spacing;
      out->axis[a].kind = nrrdKindDomain;
    }
    save_nrrd_gzip(out.get(), path);
    return;
  }
  const nifti_image* in = static_cast<const nifti_image*>(like.header.get());
  std::shared_ptr<nifti_image> out(nifti_copy_nim_info(in), [](nifti_image* p) {
    if (p) { p->data = nullptr; nifti_image_free(p); }
  });
  out->dim[0] = 3;
  for (int a = 4; a < 8; ++a) out->dim[a] = 1;
  out->datatype = DT_INT32;
  nifti_datatype_sizes(DT_INT32, &out->nbyper, &out->swapsize);
  nifti_update_dims_from_array(out.get());
  out->scl_slope = 1;
  out->scl_inter = 0;
  out->cal_min = 0;
  out->cal_max = 0;
  out->intent_code = NIFTI_INTENT_LABEL;
  std::strncpy(out->descrip, "chokeloops labels", sizeof out->descrip - 1);
  nifti_free_extensions(out.get());
  if (nifti_set_filenames(out.get(), path.c_str(), 0, 1)) throw Error("cannot name " + path, 3);
  out->data = const_cast<std::int32_t*>(labels.data());
  nifti_image_write(out.get());
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw Error("cannot write " + path, 3);
}

void write_scalar_volume(const VolumeImage& image, const std::string& path, bool compress) {
  if (metaimage::is_metaimage_path(path)) {
    metaimage::write_metaimage_scalar(image, path, compress);
    return;
  }
  std::vector<std::uint8_t> bytes = packed_values(image);
  int nifti_type = 0, nrrd_type = 0;
  if (image.datatype == "uint8") { nifti_type = DT_UINT8; nrrd_type = nrrdTypeUChar; }
  else if (image.datatype == "int16") { nifti_type = DT_INT16; nrrd_type = nrrdTypeShort; }
  else if (image.datatype == "int32") { nifti_type = DT_INT32; nrrd_type = nrrdTypeInt; }
  else { nifti_type = DT_FLOAT32; nrrd_type = nrrdTypeFloat; }
  if (is_nrrd(path)) {
    std::shared_ptr<Nrrd> out(nrrdNew(), [](Nrrd* p) { nrrdNix(p); });
    std::size_t sz[3] = {std::size_t(image.dims[0]), std::size_t(image.dims[1]), std::size_t(image.dims[2])};
    double origin[3] = {image.affine[0][3], image.affine[1][3], image.affine[2][3]};
    if (nrrdWrap_nva(out.get(), bytes.data(), nrrd_type, 3, sz) ||
        nrrdSpaceSet(out.get(), image.convention == "LPS" ? nrrdSpaceLeftPosteriorSuperior : nrrdSpaceRightAnteriorSuperior) ||
        nrrdSpaceOriginSet(out.get(), origin))
      throw Error("cannot make " + path + ": " + biff_message(), 3);
    for (int a = 0; a < 3; ++a) {
      for (int r = 0; r < 3; ++r) out->axis[a].spaceDirection[r] = image.affine[r][a];
      out->axis[a].kind = nrrdKindDomain;
    }
    save_nrrd_gzip(out.get(), path);
    return;
  }
  const int64_t dims[8] = {3, image.dims[0], image.dims[1], image.dims[2], 1, 1, 1, 1};
  std::shared_ptr<nifti_image> out(nifti_make_new_nim(dims, nifti_type, 0), [](nifti_image* p) {
    if (p) { p->data = nullptr; nifti_image_free(p); }
  });
  if (!out) throw Error("cannot make " + path, 3);
  nifti_dmat44 m;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) m.m[r][c] = r < 3 ? image.affine[r][c] : (c == 3 ? 1.0 : 0.0);
  out->sform_code = NIFTI_XFORM_SCANNER_ANAT;
  out->sto_xyz = m;
  out->sto_ijk = nifti_dmat44_inverse(m);
  out->qform_code = NIFTI_XFORM_SCANNER_ANAT;
  nifti_dmat44_to_quatern(m, &out->quatern_b, &out->quatern_c, &out->quatern_d, &out->qoffset_x, &out->qoffset_y,
                          &out->qoffset_z, &out->dx, &out->dy, &out->dz, &out->qfac);
  out->qto_xyz = nifti_quatern_to_dmat44(out->quatern_b, out->quatern_c, out->quatern_d, out->qoffset_x,
                                         out->qoffset_y, out->qoffset_z, out->dx, out->dy, out->dz, out->qfac);
  out->pixdim[1] = out->dx, out->pixdim[2] = out->dy, out->pixdim[3] = out->dz;
  out->xyz_units = NIFTI_UNITS_MM;
  if (nifti_set_filenames(out.get(), path.c_str(), 0, 1)) throw Error("cannot name " + path, 3);
  out->data = bytes.data();
  nifti_image_write(out.get());
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw Error("cannot write " + path, 3);
}

namespace {

bool store_by_nifti_type(int type, void* data, std::size_t i, double v) {
  switch (type) {
    case DT_UINT8: store<std::uint8_t>(data, i, v); return true;
    case DT_INT8: store<std::int8_t>(data, i, v); return true;
    case DT_UINT16: store<std::uint16_t>(data, i, v); return true;
    case DT_INT16: store<std::int16_t>(data, i, v); return true;
    case DT_UINT32: store<std::uint32_t>(data, i, v); return true;
    case DT_INT32: store<std::int32_t>(data, i, v); return true;
    case DT_UINT64: store<std::uint64_t>(data, i, v); return true;
    case DT_INT64: store<std::int64_t>(data, i, v); return true;
    case DT_FLOAT32: store<float>(data, i, v); return true;
    case DT_FLOAT64: store<double>(data, i, v); return true;
    default: return false;
  }
}

bool store_by_nrrd_type(int type, void* data, std::size_t i, double v) {
  switch (type) {
    case nrrdTypeUChar: store<unsigned char>(data, i, v); return true;
    case nrrdTypeChar: store<signed char>(data, i, v); return true;
    case nrrdTypeUShort: store<unsigned short>(data, i, v); return true;
    case nrrdTypeShort: store<short>(data, i, v); return true;
    case nrrdTypeUInt: store<unsigned int>(data, i, v); return true;
    case nrrdTypeInt: store<int>(data, i, v); return true;
    case nrrdTypeULLong: store<unsigned long long>(data, i, v); return true;
    case nrrdTypeLLong: store<long long>(data, i, v); return true;
    case nrrdTypeFloat: store<float>(data, i, v); return true;
    case nrrdTypeDouble: store<double>(data, i, v); return true;
    default: return false;
  }
}

}  // namespace

void write_edited_volume(const VolumeImage& like, const std::vector<std::pair<std::int64_t, double>>& changes,
                         const std::string& path) {
  if (like.format == "metaimage") {
    metaimage::write_metaimage_edited(like, changes, path);
    return;
  }
  const std::size_t offset = std::size_t(like.volume) * std::size_t(like.voxel_count());
  if (like.format == "nrrd") {
    if (!is_nrrd(path)) throw Error(path + ": the input is NRRD; write the filtered image as .nrrd");
    std::shared_ptr<Nrrd> nrrd(nrrdNew(), [](Nrrd* p) { nrrdNuke(p); });
    if (nrrdLoad(nrrd.get(), like.path.c_str(), nullptr)) throw Error(like.path + ": cannot read again: " + biff_message());
    for (const auto& [i, v] : changes)
      if (!store_by_nrrd_type(nrrd->type, nrrd->data, offset + std::size_t(i), v))
        throw Error(like.path + ": cannot write this NRRD type back");
    save_nrrd_gzip(nrrd.get(), path);
    return;
  }
  if (!is_nifti(path)) throw Error(path + ": the input is NIfTI; write the filtered image as .nii or .nii.gz");
  std::shared_ptr<nifti_image> nim(nifti_image_read(like.path.c_str(), 1), [](nifti_image* p) { if (p) nifti_image_free(p); });
  if (!nim || !nim->data) throw Error(like.path + ": cannot read again");
  const double slope = nim->scl_slope != 0 && std::isfinite(nim->scl_slope) ? nim->scl_slope : 1.0;
  const double inter = std::isfinite(nim->scl_inter) && nim->scl_slope != 0 ? nim->scl_inter : 0.0;
  for (const auto& [i, v] : changes)
    if (!store_by_nifti_type(nim->datatype, nim->data, offset + std::size_t(i), (v - inter) / slope))
      throw Error(like.path + ": cannot write this NIfTI datatype back");
  if (nifti_set_filenames(nim.get(), path.c_str(), 0, 1)) throw Error("cannot name " + path, 3);
  nifti_image_write(nim.get());
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw Error("cannot write " + path, 3);
}

}  // namespace chokeloops
