#pragma once
// Medical volumes in and out: NIfTI-1/2 (.nii, .nii.gz, .hdr/.img) through niftilib (nifti2_io), NRRD
// (.nrrd, .nhdr) through teem's nrrd, MetaImage (.mha, .mhd with .raw/.zraw) through ITK's MetaIO. One 3D
// scalar volume is read as float, with the image's index-to-world transform (DESIGN §6 "Volumes"); label
// volumes are written on the input's grid and header, in the input's format.
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace chokeloops {

struct VolumeImage {
  std::string path;
  std::string format;                    // "nifti1", "nifti2", "nrrd", "metaimage"
  std::array<int, 3> dims{0, 0, 0};      // voxels along i, j, k
  int volumes = 1;                       // length of the 4th axis (1: a 3D image)
  int volume = 0;                        // which of them `values` holds
  std::string datatype;                  // stored type, e.g. "uint8", "float32"
  bool integer_type = false;
  std::vector<float> values;             // one 3D volume, i fastest, scaling (scl_slope/inter) applied
  // Voxel (i,j,k) -> world millimetres: x = affine[r][0]*i + affine[r][1]*j + affine[r][2]*k + affine[r][3].
  std::array<std::array<double, 4>, 3> affine{};
  std::string convention;                // "RAS" (NIfTI), "LPS" (DICOM-style NRRD, MetaImage), ...
  std::string transform_source;          // "sform", "qform", "pixdim", "space directions", "TransformMatrix/Offset", ...
  std::array<double, 3> spacing{1, 1, 1};  // column norms of the affine's 3x3 part (mm)
  std::vector<std::string> warnings;
  std::shared_ptr<void> header;          // the library's own header, kept to write volumes like this one

  std::int64_t voxel_count() const { return std::int64_t(dims[0]) * dims[1] * dims[2]; }
  std::array<double, 3> to_world(double i, double j, double k) const {
    std::array<double, 3> x;
    for (int r = 0; r < 3; ++r) x[r] = affine[r][0] * i + affine[r][1] * j + affine[r][2] * k + affine[r][3];
    return x;
  }
};

// Whether the path names a volume this reader takes (by extension).
bool is_volume_path(const std::string& path);

// Reads the image; `volume` picks one 3D volume of a 4D image (-1: the image must be 3D); a MetaImage's
// 4th dimension or its channels (ElementNumberOfChannels > 1) are its volumes. Throws Error(2) naming the
// file and the field at fault: unreadable/truncated file, compressed data that does not inflate, dims < 2
// or inconsistent, unsupported datatype, NaN/Inf values, 4D without a volume, a singular transform; Error(3)
// when one volume needs more than the memory allowed.
VolumeImage read_volume(const std::string& path, int volume = -1);

// Writes a label volume (one int32 per voxel, i fastest, like.voxel_count() of them) on `like`'s grid
// and header, in its format: NIfTI as .nii/.nii.gz (by `path`), NRRD as .nrrd, MetaImage as .mha.
void write_label_volume(const VolumeImage& like, const std::vector<std::int32_t>& labels, const std::string& path);

// Writes a scalar image (image.dims, image.affine as sform and qform, image.values converted to
// image.datatype: "uint8", "int16", "int32", "float32") as NIfTI-1 (.nii/.nii.gz) or NRRD (.nrrd, LPS taken
// as the affine's space when image.convention is "LPS", else RAS), or MetaImage (.mha, or .mhd with a .raw
// data file; MetaImage's world is LPS: an affine of convention "RAS" is turned into LPS, any other is
// written as it is). `compress` is for MetaImage only (CompressedData = True, .zraw beside a .mhd): NIfTI is
// compressed by naming it .nii.gz, NRRD always is. For tests, benchmarks and tools.
void write_scalar_volume(const VolumeImage& image, const std::string& path, bool compress = false);

// Writes the image `like` was read from (every volume of it, its header and datatype) to `path`, in the same
// format, with the voxels in `changes` (linear index in `like`'s 3D volume, new value in the image's scaled
// units) set in the volume `like` holds; every other byte of data unchanged. Throws Error (2) when `path` is
// not of the input's format, (3) when it cannot be written. A MetaImage input may be written as .mha (one
// file) or .mhd (with a .raw, or .zraw when the input is compressed, beside it), whichever `path` names.
void write_edited_volume(const VolumeImage& like, const std::vector<std::pair<std::int64_t, double>>& changes,
                         const std::string& path);

// The file name a label volume called `stem` gets next to an input of this format: "loops.nii.gz",
// "loops.nrrd", "loops.mha" (for .mha and .mhd inputs alike).
std::string label_volume_name(const VolumeImage& like, const std::string& stem);

}  // namespace chokeloops
