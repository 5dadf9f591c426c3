// MetaImage volumes (.mha, .mhd + .raw/.zraw) through MetaIO: world positions through a TransformMatrix
// written by hand in ITK's storage order, round trips, --labels all and filter on .mha files, and bad input
// as one-line errors with exit code 2.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <iterator>
#include <sstream>

#include <nlohmann/json.hpp>

#include "chokeloops/analyze_volume.h"
#include "chokeloops/filter/filter_file.h"
#include "chokeloops/io/volume_io.h"
#include "temp_dir.h"
#include "volume_checks.h"
#include "volume_images.h"

using namespace chokeloops;
using chokeloops::test::make_image;
namespace fs = std::filesystem;

namespace {

fs::path temp_dir(const std::string& name) { return test::temp_dir("metaimage_" + name); }

std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// A .mha written without MetaIO: `fields` (one "Key = value" per line, ending with ElementDataFile = LOCAL)
// followed by `data`. The reader's conventions are checked against the format itself, not against our writer.
std::string write_mha(const fs::path& dir, const std::string& name, const std::string& fields, const std::string& data) {
  return test::write_file(dir, name, "ObjectType = Image\n" + fields + data);
}

template <class T>
std::string bytes_of(const std::vector<T>& v) {
  return std::string(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
}

std::string numbers(std::initializer_list<double> xs) {
  std::ostringstream s;
  s << std::setprecision(17);
  for (double x : xs) s << (s.tellp() > 0 ? " " : "") << x;
  return s.str();
}

// Runs the CLI; returns its exit code, with stderr in `err`.
int cli(const std::string& args, std::string& err, const fs::path& dir) {
  const std::string e = (dir / "err.txt").string();
  const int status = std::system((std::string("'") + CHOKELOOPS_CLI + "' " + args + " --quiet 2>'" + e + "' >/dev/null").c_str());
  err = read_text(e);
  return WEXITSTATUS(status);
}

void expect_bad(const std::string& path, const std::string& needle, int volume = -1) {
  try {
    read_volume(path, volume);
    ADD_FAILURE() << path << ": no error; expected one naming '" << needle << "'";
  } catch (const Error& e) {
    EXPECT_EQ(e.exit_code, 2) << e.what();
    const std::string m = e.what();
    EXPECT_NE(m.find(needle), std::string::npos) << m;
    EXPECT_EQ(m.find(path), 0u) << m;  // the line starts with the file's name
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
  }
}

// The 30 degree rotation about (1,2,3) of the NIfTI oblique test; not symmetric, so reading TransformMatrix
// transposed moves every position.
struct Rotation {
  double m[3][3];
  Rotation() {
    const double ang = M_PI / 6, n0 = 1 / std::sqrt(14.0), n1 = 2 / std::sqrt(14.0), n2 = 3 / std::sqrt(14.0);
    const double cs = std::cos(ang), sn = std::sin(ang), t = 1 - cs;
    const double r[3][3] = {{cs + n0 * n0 * t, n0 * n1 * t - n2 * sn, n0 * n2 * t + n1 * sn},
                            {n1 * n0 * t + n2 * sn, cs + n1 * n1 * t, n1 * n2 * t - n0 * sn},
                            {n2 * n0 * t - n1 * sn, n2 * n1 * t + n0 * sn, cs + n2 * n2 * t}};
    std::memcpy(m, r, sizeof m);
  }
  // ITK's TransformMatrix: the direction of axis 0, then of axis 1, then of axis 2 (the matrix's columns).
  std::string transform_matrix() const {
    return numbers({m[0][0], m[1][0], m[2][0], m[0][1], m[1][1], m[2][1], m[0][2], m[1][2], m[2][2]});
  }
};

}  // namespace

TEST(MetaImageWorld, HandWrittenObliqueTransformMatrixPutsLoopsAtKnownLpsPositions) {
  const fs::path d = temp_dir("oblique");
  const std::array<double, 3> h{0.7, 1.0, 1.5}, c{22, 24, 21};
  const double R = 12, rr = 5, off[3] = {-50, 20, 10};
  const Rotation rot;
  const auto img =
      make_image({64, 48, 29}, h, "uint8", [&](double x, double y, double z) { return test::torus(x, y, z, c, R, rr); });
  std::vector<std::uint8_t> data(img.values.begin(), img.values.end());
  const std::string path = write_mha(d, "oblique.mha",
                                     "NDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\nCompressedData = False\n"
                                     "TransformMatrix = " + rot.transform_matrix() + "\nOffset = " +
                                         numbers({off[0], off[1], off[2]}) + "\nAnatomicalOrientation = RAS\n"
                                         "ElementSpacing = " + numbers({h[0], h[1], h[2]}) +
                                         "\nDimSize = 64 48 29\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n",
                                     bytes_of(data));
  const VolumeImage in = read_volume(path);
  EXPECT_EQ(in.format, "metaimage");
  EXPECT_EQ(in.convention, "LPS");
  EXPECT_EQ(in.transform_source, "TransformMatrix/Offset");
  EXPECT_EQ(in.datatype, "uint8");
  // index -> world = direction * diag(spacing) | Offset, the direction's columns read as consecutive triples
  for (int r = 0; r < 3; ++r) {
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(in.affine[r][a], rot.m[r][a] * h[a], 1e-12) << r << "," << a;
    EXPECT_DOUBLE_EQ(in.affine[r][3], off[r]);
  }
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(in.spacing[a], h[a], 1e-12);
  // The matrix keeps each axis nearest to +x, +y, +z (ITK's RAI); the header's RAS says the third axis runs
  // down: the reader says so and follows the matrix.
  ASSERT_EQ(in.warnings.size(), 1u);
  EXPECT_NE(in.warnings[0].find("AnatomicalOrientation RAS disagrees with TransformMatrix (RAI)"), std::string::npos)
      << in.warnings[0];

  const VolumeAnalysis a = analyze_volume(in, test::label(1), {});
  const AnalyzeResult& r = a.result;
  EXPECT_EQ(r.surface_stats.genus, 1);
  // Positions in LPS world mm: those of the torus rotated by the matrix read as ITK reads it.
  std::array<double, 3> centre;
  for (int q = 0; q < 3; ++q) centre[q] = rot.m[q][0] * c[0] + rot.m[q][1] * c[1] + rot.m[q][2] * c[2] + off[q];
  const auto [hl, tl] = test::expect_torus_generator_loops(r, centre, R, rr);
  ASSERT_TRUE(hl && tl);
  // Choke points: the tunnel's where the hole closes last, its centre (R - r from the tube); the handle's in
  // the tube, on the centre circle (r deep).
  EXPECT_LT(test::dist(r.frame.apply(tl->choke.point), centre), 1.5);
  EXPECT_NEAR(tl->choke.depth, R - rr, 1.0);
  EXPECT_NEAR(test::dist(r.frame.apply(hl->choke.point), centre), R, 1.5);
  EXPECT_NEAR(hl->choke.depth, rr, 1.0);

  write_report(r, {}, (d / "out").string());
  const auto names = write_loop_volumes(a, in, (d / "out").string()).files;
  ASSERT_EQ(names[0], "loops.mha");
  nlohmann::json j;
  std::ifstream(d / "out" / "loops.json") >> j;
  EXPECT_EQ(j["coordinates"]["convention"], "LPS");
  EXPECT_EQ(j["coordinates"]["source"], "TransformMatrix/Offset");
  EXPECT_EQ(j["volume"]["format"], "metaimage");
  const auto& jt = j["loops"][int(tl - r.loops.data())]["centroid"];
  EXPECT_LT(test::dist({jt[0].get<double>(), jt[1].get<double>(), jt[2].get<double>()}, centre), 1.0);
  // loops.mha: the input's grid; the tunnel loop's voxels around the torus centre
  const VolumeImage lv = read_volume((d / "out" / "loops.mha").string());
  EXPECT_EQ(lv.datatype, "int32");
  EXPECT_EQ(lv.dims, in.dims);
  for (int q = 0; q < 3; ++q)
    for (int k = 0; k < 4; ++k) EXPECT_NEAR(lv.affine[q][k], in.affine[q][k], 1e-12);
  const int tid = int(tl - r.loops.data()) + 1;
  int n = 0;
  std::array<double, 3> sum{0, 0, 0};
  for (int k = 0; k < lv.dims[2]; ++k)
    for (int jj = 0; jj < lv.dims[1]; ++jj)
      for (int i = 0; i < lv.dims[0]; ++i)
        if (lv.values[std::size_t(i) + std::size_t(lv.dims[0]) * (jj + std::size_t(lv.dims[1]) * k)] == tid) {
          const auto w = lv.to_world(i, jj, k);
          for (int q = 0; q < 3; ++q) sum[q] += w[q];
          ++n;
        }
  ASSERT_GT(n, 10);
  EXPECT_LT(test::dist({sum[0] / n, sum[1] / n, sum[2] / n}, centre), 1.5);
  fs::remove_all(d);
}

TEST(MetaImageRoundTrip, MhaCompressedMhaAndDetachedMhdKeepValuesDimsAndAffine) {
  const fs::path d = temp_dir("roundtrip");
  auto img = make_image({7, 6, 5}, {0.5, 1.25, 2}, "int16", [](double x, double y, double z) { return float(8 * x - 4 * y + z) - 20; });
  img.convention = "LPS";
  const Rotation rot;
  for (int r = 0; r < 3; ++r) {
    for (int a = 0; a < 3; ++a) img.affine[r][a] = rot.m[r][a] * std::array<double, 3>{0.5, 1.25, 2}[a];
    img.affine[r][3] = 10.0 * r - 7.5;
  }
  struct Variant {
    std::string name, data_file;
    bool compress;
  };
  for (const Variant& v : {Variant{"plain.mha", "", false}, Variant{"packed.mha", "", true},
                           Variant{"detached.mhd", "detached.raw", false}, Variant{"zipped.mhd", "zipped.zraw", true}}) {
    SCOPED_TRACE(v.name);
    write_scalar_volume(img, (d / v.name).string(), v.compress);
    const std::string header = read_text(d / v.name);
    EXPECT_NE(header.find(v.compress ? "CompressedData = True" : "CompressedData = False"), std::string::npos);
    EXPECT_NE(header.find("ElementType = MET_SHORT"), std::string::npos);
    if (!v.data_file.empty()) {
      EXPECT_TRUE(fs::is_regular_file(d / v.data_file));
      EXPECT_NE(header.find("ElementDataFile = " + v.data_file), std::string::npos);
    }
    const VolumeImage back = read_volume((d / v.name).string());
    EXPECT_EQ(back.datatype, "int16");
    EXPECT_EQ(back.dims, img.dims);
    EXPECT_EQ(back.convention, "LPS");
    ASSERT_EQ(back.values.size(), img.values.size());
    for (std::size_t i = 0; i < img.values.size(); ++i) ASSERT_EQ(back.values[i], img.values[i]) << i;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) EXPECT_NEAR(back.affine[r][c], img.affine[r][c], 1e-12);
    EXPECT_TRUE(back.warnings.empty()) << back.warnings[0];  // AnatomicalOrientation written to agree
  }
  // An RAS affine is written as the same physical points in MetaImage's LPS: x and y change sign.
  auto ras = img;
  ras.convention = "RAS";
  write_scalar_volume(ras, (d / "ras.mha").string());
  const VolumeImage lps = read_volume((d / "ras.mha").string());
  for (int c = 0; c < 4; ++c) {
    EXPECT_NEAR(lps.affine[0][c], -img.affine[0][c], 1e-12);
    EXPECT_NEAR(lps.affine[1][c], -img.affine[1][c], 1e-12);
    EXPECT_NEAR(lps.affine[2][c], img.affine[2][c], 1e-12);
  }
  fs::remove_all(d);
}

TEST(MetaImageRoundTrip, BigEndianChannelsAndFourthDimensionAreReadAsStored) {
  const fs::path d = temp_dir("layout");
  const std::string grid = "ElementSpacing = 1 1 1\nDimSize = 2 2 2\n";
  // big-endian int16: 0x0102 = 258, then 0xFFFE = -2, ...
  std::string be;
  for (int i = 0; i < 8; ++i) {
    const std::int16_t x = std::int16_t(i == 1 ? -2 : 258 + i);
    be += char((std::uint16_t(x) >> 8) & 0xff);
    be += char(std::uint16_t(x) & 0xff);
  }
  const VolumeImage msb = read_volume(write_mha(d, "msb.mha", "NDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = True\n" + grid +
                                                                   "ElementType = MET_SHORT\nElementDataFile = LOCAL\n", be));
  EXPECT_EQ(msb.values[0], 258.f);
  EXPECT_EQ(msb.values[1], -2.f);
  EXPECT_EQ(msb.values[7], 265.f);
  // three interleaved channels: channel K of voxel i is 100 K + i; --volume K picks it
  std::vector<float> rgb;
  for (int i = 0; i < 8; ++i)
    for (int k = 0; k < 3; ++k) rgb.push_back(float(100 * k + i));
  const std::string channels = write_mha(d, "rgb.mha", "NDims = 3\nBinaryData = True\nElementNumberOfChannels = 3\n" + grid +
                                                           "ElementType = MET_FLOAT\nElementDataFile = LOCAL\n", bytes_of(rgb));
  expect_bad(channels, "ElementNumberOfChannels");
  const VolumeImage green = read_volume(channels, 1);
  EXPECT_EQ(green.volumes, 3);
  for (int i = 0; i < 8; ++i) EXPECT_EQ(green.values[std::size_t(i)], float(100 + i));
  // NDims 4: the 4th axis is the slowest; volume K is the K-th block of 8 voxels
  std::vector<std::uint8_t> four;
  for (int i = 0; i < 8 * 4; ++i) four.push_back(std::uint8_t(i));
  const std::string fourd = write_mha(d, "4d.mha", "NDims = 4\nBinaryData = True\nElementSpacing = 1 1 1 1\nDimSize = 2 2 2 4\n"
                                                    "ElementType = MET_UCHAR\nElementDataFile = LOCAL\n", bytes_of(four));
  expect_bad(fourd, "--volume");
  expect_bad(fourd, "--volume 4 is past", 4);
  const VolumeImage third = read_volume(fourd, 2);
  EXPECT_EQ(third.volumes, 4);
  EXPECT_EQ(third.dims, (std::array<int, 3>{2, 2, 2}));
  for (int i = 0; i < 8; ++i) EXPECT_EQ(third.values[std::size_t(i)], float(16 + i));
  fs::remove_all(d);
}

TEST(MetaImageLabels, LabelsAllOnAMhaLabelMapWritesLoopsMhaOnTheInputGrid) {
  const fs::path d = temp_dir("labels");
  // label 1: a torus (one handle) around (20,20,12) mm; label 2: a ball (none), on an anisotropic,
  // axis-swapped LPS grid.
  const std::array<double, 3> h{1.0, 1.0, 1.5}, c{20, 20, 12};
  auto map = make_image({40, 40, 24}, h, "int16", [&](double x, double y, double z) {
    if (test::torus(x, y, z, c, 10, 4) > 0) return 1.f;
    return std::hypot(std::hypot(x - 34, y - 34), z - 27) <= 4 ? 2.f : 0.f;
  });
  map.convention = "LPS";
  map.affine = {{{0, -1.0, 0, 100}, {1.0, 0, 0, -40}, {0, 0, 1.5, 5}}};  // i along +y, j along -x
  const std::string in = (d / "map.mha").string(), out = (d / "out").string();
  write_scalar_volume(map, in, true);
  std::string err;
  ASSERT_EQ(cli("analyze '" + in + "' --labels all -o '" + out + "'", err, d), 0) << err;
  nlohmann::json index;
  std::ifstream(d / "out" / "labels.json") >> index;
  ASSERT_EQ(index["labels"].size(), 2u);
  EXPECT_EQ(index["labels"][0]["label"], 1);
  EXPECT_EQ(index["labels"][1]["label"], 2);
  nlohmann::json j;
  std::ifstream(d / "out" / "label_1" / "loops.json") >> j;
  EXPECT_EQ(j["coordinates"]["convention"], "LPS");
  EXPECT_EQ(j["surface"]["genus"], 1);
  ASSERT_TRUE(fs::is_regular_file(d / "out" / "label_1" / "loops.mha"));
  ASSERT_TRUE(fs::is_regular_file(d / "out" / "label_2" / "loops.mha"));
  EXPECT_FALSE(fs::exists(d / "out" / "label_1" / "loops.nii.gz"));
  const VolumeImage image = read_volume(in);
  const VolumeImage loops = read_volume((d / "out" / "label_1" / "loops.mha").string());
  EXPECT_EQ(loops.dims, image.dims);
  for (int q = 0; q < 3; ++q)
    for (int k = 0; k < 4; ++k) EXPECT_NEAR(loops.affine[q][k], image.affine[q][k], 1e-12);
  // Every loop voxel lies on the torus (within a voxel of its surface), and there are enough to draw two loops.
  const std::array<double, 3> centre = image.to_world(c[0] / h[0], c[1] / h[1], c[2] / h[2]);
  int marked = 0;
  for (int k = 0; k < loops.dims[2]; ++k)
    for (int jj = 0; jj < loops.dims[1]; ++jj)
      for (int i = 0; i < loops.dims[0]; ++i) {
        const float id = loops.values[std::size_t(i) + std::size_t(loops.dims[0]) * (jj + std::size_t(loops.dims[1]) * k)];
        if (id == 0) continue;
        ++marked;
        const auto w = image.to_world(i, jj, k);
        // the torus axis is the world z axis (k is along z): distance from the tube's centre circle
        const double q = std::hypot(w[0] - centre[0], w[1] - centre[1]) - 10;
        EXPECT_LE(std::abs(std::hypot(q, w[2] - centre[2]) - 4), 2.0) << i << "," << jj << "," << k;
      }
  EXPECT_GT(marked, 30);
  const VolumeImage ball = read_volume((d / "out" / "label_2" / "loops.mha").string());
  EXPECT_EQ(std::count_if(ball.values.begin(), ball.values.end(), [](float x) { return x != 0; }), 0);
  fs::remove_all(d);
}

TEST(MetaImageFilter, SphereWithAOneVoxelBridgeInMhaLosesThatVoxelOnly) {
  const fs::path d = temp_dir("filter");
  const VolumeImage image = test::sphere_with_bridge(40, 40);
  auto lps = image;
  lps.convention = "LPS";
  lps.affine = {{{0.8, 0, 0, -12}, {0, 0.8, 0, 30}, {0, 0, 1.2, -4}}};
  const std::string in = (d / "b.mha").string(), out = (d / "f.mha").string();
  write_scalar_volume(lps, in);
  std::string err;
  ASSERT_EQ(cli("filter '" + in + "' -o '" + out + "' --label 1 --keep-genus 0", err, d), 0) << err;
  const VolumeImage back = read_volume(out);
  EXPECT_EQ(back.format, "metaimage");
  EXPECT_EQ(back.datatype, "uint8");
  EXPECT_EQ(back.dims, image.dims);
  EXPECT_EQ(back.affine, read_volume(in).affine);
  std::size_t changed = 0, at = 0;
  for (std::size_t i = 0; i < back.values.size(); ++i)
    if (back.values[i] != image.values[i]) ++changed, at = i;
  EXPECT_EQ(changed, 1u);  // the bridge voxel, and nothing else
  EXPECT_EQ(back.values[at], 0.f);
  // the header lines that place the image are the input's, byte for byte
  const std::string hin = read_text(in), hout = read_text(out);
  for (const std::string key : {"TransformMatrix = ", "Offset = ", "ElementSpacing = ", "DimSize = ", "ElementType = MET_UCHAR"}) {
    const auto line = [&](const std::string& t) { const auto p = t.find(key); return p == std::string::npos ? std::string() : t.substr(p, t.find('\n', p) - p); };
    EXPECT_FALSE(line(hout).empty()) << key;
    EXPECT_EQ(line(hout), line(hin));
  }
  // a compressed .mhd stays a compressed .mhd (a .zraw beside it) through filter_file
  write_scalar_volume(lps, (d / "z.mhd").string(), true);
  FilterFileOptions o;
  o.field.has_label = true;
  o.field.label = 1;
  o.filter.keep_genus = 0;
  const FilterFileResult r = filter_file((d / "z.mhd").string(), (d / "g.mhd").string(), o);
  EXPECT_EQ(r.report.voxels_changed, 1u);
  EXPECT_EQ(r.output_check.genus, 0);
  EXPECT_TRUE(fs::is_regular_file(d / "g.zraw"));
  EXPECT_NE(read_text(d / "g.mhd").find("CompressedData = True"), std::string::npos);
  EXPECT_EQ(read_volume((d / "g.mhd").string()).values, back.values);
  // and a MetaImage input is not filtered into another format
  EXPECT_NE(cli("filter '" + in + "' -o '" + (d / "f.nii.gz").string() + "' --label 1 --keep-genus 0", err, d), 0);
  EXPECT_NE(err.find(".mha"), std::string::npos) << err;
  fs::remove_all(d);
}

TEST(MetaImageBadInput, OneLineErrorsWithExitCode2) {
  const fs::path d = temp_dir("bad");
  auto img = make_image({8, 8, 8}, {1, 1, 1}, "float32", [](double x, double, double) { return float(x); });
  img.convention = "LPS";
  const auto copy_with = [&](const std::string& from, const std::string& to, const std::string& was, const std::string& now) {
    std::string t = read_text(d / from);
    const auto p = t.find(was);
    EXPECT_NE(p, std::string::npos) << was;
    if (p != std::string::npos) t.replace(p, was.size(), now);
    return test::write_file(d, to, t);
  };
  // truncated inline data
  write_scalar_volume(img, (d / "ok.mha").string());
  fs::copy_file(d / "ok.mha", d / "short.mha");
  fs::resize_file(d / "short.mha", fs::file_size(d / "ok.mha") - 5);
  expect_bad((d / "short.mha").string(), "shorter than DimSize x ElementType");
  // compressed data cut short, and compressed data that is not a deflate stream
  write_scalar_volume(img, (d / "z.mha").string(), true);
  fs::copy_file(d / "z.mha", d / "zshort.mha");
  fs::resize_file(d / "zshort.mha", fs::file_size(d / "z.mha") - 9);
  expect_bad((d / "zshort.mha").string(), "CompressedDataSize");
  {
    std::string t = read_text(d / "z.mha");
    const std::size_t data = t.find("ElementDataFile = LOCAL\n") + 24;
    for (std::size_t i = data + 2; i < t.size(); i += 3) t[i] = char(t[i] ^ 0x5a);
    test::write_file(d, "zbad.mha", t);
  }
  expect_bad((d / "zbad.mha").string(), "does not inflate");
  // a .mhd whose data file is missing
  write_scalar_volume(img, (d / "detached.mhd").string());
  fs::remove(d / "detached.raw");
  expect_bad((d / "detached.mhd").string(), "ElementDataFile detached.raw");
  // NDims 2, unsupported element types
  expect_bad(write_mha(d, "flat.mha", "NDims = 2\nDimSize = 4 4\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n",
                       std::string(16, '\1')),
             "NDims = 2");
  expect_bad(copy_with("ok.mha", "string.mha", "MET_FLOAT", "MET_STRING"), "ElementType MET_STRING");
  expect_bad(copy_with("ok.mha", "vector.mha", "MET_FLOAT", "MET_FLOAT_ARRAY"), "ElementType MET_FLOAT_ARRAY");
  // NaN and infinity in MET_FLOAT
  img.values[3 + 8 * (2 + 8 * 1)] = NAN;
  write_scalar_volume(img, (d / "nan.mha").string());
  expect_bad((d / "nan.mha").string(), "voxel (3,2,1) is NaN");
  img.values[3 + 8 * (2 + 8 * 1)] = INFINITY;
  write_scalar_volume(img, (d / "inf.mhd").string(), true);
  expect_bad((d / "inf.mhd").string(), "infinite");
  // DimSize: more than the data holds, a product past 64 bits, a size past int, a single slice
  expect_bad(copy_with("ok.mha", "more.mha", "DimSize = 8 8 8", "DimSize = 8 8 9"), "shorter than DimSize x ElementType");
  expect_bad(copy_with("ok.mha", "huge.mha", "DimSize = 8 8 8", "DimSize = 1048576 1048576 1048576"), "shorter than");
  expect_bad(copy_with("ok.mha", "wide.mha", "DimSize = 8 8 8", "DimSize = 8 8 4000000000"), "DimSize[2]");
  expect_bad(copy_with("ok.mha", "slice.mha", "DimSize = 8 8 8", "DimSize = 8 64 1"), "at least 2 voxels");
  expect_bad(copy_with("z.mha", "zhuge.mha", "DimSize = 8 8 8", "DimSize = 8000 8000 8000"), "cannot hold");
  // a singular TransformMatrix (two axes along x), and a header MetaIO cannot parse
  expect_bad(copy_with("ok.mha", "singular.mha", "TransformMatrix = 1 0 0 0 1 0 0 0 1", "TransformMatrix = 1 0 0 1 0 0 0 0 1"),
             "singular");
  expect_bad(test::write_file(d, "text.mha", "this is not a MetaImage\n"), "not a readable MetaImage header");
  // the CLI: exit code 2 and exactly one line on stderr (MetaIO's own complaints kept off it)
  for (const std::string bad : {"text.mha", "zbad.mha", "detached.mhd"}) {
    std::string err;
    EXPECT_EQ(cli("analyze '" + (d / bad).string() + "' --label 1 -o '" + (d / "o").string() + "'", err, d), 2) << bad;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
    EXPECT_NE(err.find(bad), std::string::npos) << err;
  }
  fs::remove_all(d);
}

// Found by fuzzing MetaIO 5.2's header parser: a negative NDims made it read ~2^64 numbers (a hang), NDims
// written on a line of its own made it take the next line's value, and a field name or value of 255 bytes or
// more overflowed its fixed buffers (an abort). Each is refused before MetaIO reads the file.
TEST(MetaImageBadInput, FuzzFindingsAreRefusedBeforeMetaIOParsesTheHeader) {
  const fs::path d = temp_dir("fuzzed");
  const std::string rest = "ElementSpacing = 1 1 1\nDimSize = 2 2 2\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n";
  const std::string data(8, '\1');
  expect_bad(write_mha(d, "negative.mha", "NDims = -1\n" + rest, data), "NDims = -1 is not a number of dimensions");
  expect_bad(write_mha(d, "eleven.mha", "NDims = 11\n" + rest, data), "NDims = 11");
  expect_bad(write_mha(d, "split.mha", "NDims \nHeaderSize = -1\n" + rest, data), "NDims =  is not");
  expect_bad(write_mha(d, "name.mha", "NDims = 3\n" + std::string(300, 'F') + " = 1\n" + rest, data), "header line 3 is 304 bytes");
  expect_bad(write_mha(d, "comment.mha", "NDims = 3\nComment = " + std::string(260, 'c') + "\n" + rest, data), "header line 3");
  // the corpus' own findings, as stored
  // a name alone on its line: MetaIO takes the next line as its value, so an ElementDataFile line there does not end
  // its header (regression-8cc5550860d4: a negative NDims further down, a timeout)
  expect_bad(write_mha(d, "alone.mha", "Comment\nElementDataFile = LOCAL\nNDims = -1\n" + rest, data),
             "('Comment') has no '=' and value");
  for (const std::string name : {"regression-2642f2e70dbd", "regression-d3cb28ea4b4a", "regression-ndims-negative",
                                 "regression-8cc5550860d4"}) {
    const std::string bytes = read_text(fs::path(CHOKELOOPS_SOURCE_DIR) / "fuzz" / "corpus" / "mha" / name);
    ASSERT_FALSE(bytes.empty()) << name;
    expect_bad(test::write_file(d, name + ".mha", bytes), name);
  }
  // a header just inside the limits is read
  const VolumeImage ok = read_volume(write_mha(d, "ok.mha", "NDims = 3\nComment = " + std::string(200, 'c') + "\n" + rest, data));
  EXPECT_EQ(ok.values[7], 1.f);
  fs::remove_all(d);
}
