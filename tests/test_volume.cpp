// Medical volumes: NIfTI/NRRD in, masks with known answers, world coordinates through an oblique
// sform with anisotropic spacing, label volumes out, bad input as one-line errors with exit code 2.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <iterator>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>

#include <nifti/nifti2_io.h>
#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include "chokeloops/analyze_volume.h"
#include "chokeloops/io/volume_io.h"
#include "chokeloops/loops/membrane_voxels.h"
#include "chokeloops/topology/complex.h"
#include "temp_dir.h"
#include "volume_checks.h"
#include "volume_images.h"

using namespace chokeloops;
using chokeloops::test::dist;
using chokeloops::test::find_loop;
using chokeloops::test::label;
using chokeloops::test::make_image;
using chokeloops::test::sphere_with_bridge;
using chokeloops::test::torus;
namespace fs = std::filesystem;

namespace {

fs::path temp_dir(const std::string& name) { return test::temp_dir("volume_" + name); }

VolumeAnalysis analyze_file(const std::string& path, VolumeFieldOptions f, AnalyzeOptions o = {}) {
  VolumeImage img = read_volume(path);
  return analyze_volume(img, f, o);
}

// A torus mask (R 12, r 5 mm, axis along the image's k) on a 64x48x29 lattice of spacing 0.7 x 1 x 1.5 mm,
// rotated by 30 degrees about (1,2,3)/|.| and offset in world: direction * spacing as the sform.
struct ObliqueTorus {
  VolumeImage image;
  std::array<std::array<double, 3>, 3> rotation;
  std::array<double, 3> centre_world;
};

ObliqueTorus oblique_torus() {
  const std::array<double, 3> h{0.7, 1.0, 1.5}, c{22, 24, 21};
  ObliqueTorus ot;
  ot.image = make_image({64, 48, 29}, h, "uint8", [&](double x, double y, double z) { return torus(x, y, z, c, 12, 5); });
  const double ang = M_PI / 6, n0 = 1 / std::sqrt(14.0), n1 = 2 / std::sqrt(14.0), n2 = 3 / std::sqrt(14.0);
  const double cs = std::cos(ang), sn = std::sin(ang), t = 1 - cs;
  ot.rotation = {{{cs + n0 * n0 * t, n0 * n1 * t - n2 * sn, n0 * n2 * t + n1 * sn},
                  {n1 * n0 * t + n2 * sn, cs + n1 * n1 * t, n1 * n2 * t - n0 * sn},
                  {n2 * n0 * t - n1 * sn, n2 * n1 * t + n0 * sn, cs + n2 * n2 * t}}};
  const double off[3] = {-50, 20, 10};
  for (int r = 0; r < 3; ++r) {
    for (int a = 0; a < 3; ++a) ot.image.affine[r][a] = ot.rotation[r][a] * h[a];
    ot.image.affine[r][3] = off[r];
    ot.centre_world[r] = ot.rotation[r][0] * c[0] + ot.rotation[r][1] * c[1] + ot.rotation[r][2] * c[2] + off[r];
  }
  return ot;
}

}  // namespace

TEST(VolumeMasks, VoxelisedTorus) {
  fs::path d = temp_dir("torus");
  auto img = make_image({64, 64, 40}, {1, 1, 1}, "uint8",
                        [](double x, double y, double z) { return torus(x, y, z, {32, 32, 20}, 16, 6); });
  write_scalar_volume(img, (d / "torus.nii.gz").string());
  VolumeAnalysis a = analyze_file((d / "torus.nii.gz").string(), label(1));
  const AnalyzeResult& r = a.result;
  EXPECT_EQ(r.surface_stats.genus, 1);
  EXPECT_EQ(r.chokes.handle_generators, 1);
  EXPECT_EQ(r.chokes.tunnel_generators, 1);
  const Loop* h = find_loop(r, Side::Handle, Kind::Generator);
  const Loop* t = find_loop(r, Side::Tunnel, Kind::Generator);
  ASSERT_TRUE(h && t);
  // Boundary halfway between voxels: the voxelised tube has radius ~6.5 voxels around a centre line of radius 16.
  EXPECT_NEAR(h->length, 2 * M_PI * 6.5, 0.1 * 2 * M_PI * 6.5);
  EXPECT_NEAR(t->length, 2 * M_PI * (16 - 6.5), 0.1 * 2 * M_PI * 9.5);
  // The handle is born where its core ring is thinnest: lattice vertices up to ~0.7 voxel off the centre
  // circle, so between r and r + 1/2 less that.
  EXPECT_GT(h->choke.depth, 4.5);
  EXPECT_LT(h->choke.depth, 6.6);
  fs::remove_all(d);
}

TEST(VolumeMasks, TubeWithStenosisNeckDepthIsItsRadius) {
  fs::path d = temp_dir("stenosis");
  // Tube along z, radius 8 voxels narrowing to 3 at z = 40, closed at z = 8 and z = 72.
  auto radius = [](double z) { return 8.0 - 5.0 * std::exp(-(z - 40) * (z - 40) / (2 * 5.0 * 5.0)); };
  auto img = make_image({32, 32, 80}, {1, 1, 1}, "uint8", [&](double x, double y, double z) {
    return z >= 8 && z <= 72 && std::hypot(x - 15.5, y - 15.5) <= radius(z) ? 1.f : 0.f;
  });
  write_scalar_volume(img, (d / "tube.nii").string());
  AnalyzeOptions o;
  o.chokes.d_max = Threshold::parse("6");  // mm
  o.chokes.min_persistence = Threshold::parse("2");
  VolumeAnalysis a = analyze_file((d / "tube.nii").string(), label(1), o);
  const AnalyzeResult& r = a.result;
  EXPECT_EQ(r.surface_stats.genus, 0);
  EXPECT_EQ(r.surface_stats.components, 1);
  const Loop* neck = find_loop(r, Side::Handle, Kind::Choke);
  ASSERT_TRUE(neck);
  int necks = 0;
  for (auto& l : r.loops) necks += l.choke.side == Side::Handle && l.choke.kind == Kind::Choke;
  EXPECT_EQ(necks, 1);
  EXPECT_NEAR(neck->choke.depth, 3.0, 1.0);  // the neck's radius, within a voxel
  EXPECT_NEAR(neck->centroid[2], 40.0, 3.0);  // on the neck's flat ridge (index tie-break picks an end)
  EXPECT_NEAR(neck->length, 2 * M_PI * 3.5, 0.15 * 2 * M_PI * 3.5);
  fs::remove_all(d);
}

namespace {
// A solid sphere (radius 10 around (24,24,24)) with a bridge of single voxels: up from its top, across at
// height z_a, then (after a one-step offset in x and z) at height z_b and down onto the sphere.
}  // namespace

TEST(VolumeMasks, SphereWithOneVoxelBridge) {
  fs::path d = temp_dir("bridge");
  write_scalar_volume(sphere_with_bridge(40, 40), (d / "b.nii.gz").string());
  VolumeAnalysis a = analyze_file((d / "b.nii.gz").string(), label(1));
  EXPECT_EQ(a.result.surface_stats.genus, 1);
  EXPECT_EQ(a.result.chokes.handle_generators, 1);
  const Loop* h = find_loop(a.result, Side::Handle, Kind::Generator);
  ASSERT_TRUE(h);
  EXPECT_NEAR(h->choke.depth, 0.5, 0.25);  // half a voxel: the strand's boundary is halfway to its neighbours
  EXPECT_LT(h->length, 5.0);               // around one voxel's cross-section
  fs::remove_all(d);
}

TEST(VolumeMasks, DiagonalContactsFollowTheFreudenthalDiagonal) {
  // (28,24,40)-(29,24,41): offset (1,0,1), an edge of the complex: the bridge holds (genus 1).
  // (28,24,41)-(29,24,40): offset (1,0,-1), not an edge: the bridge is cut (genus 0). Either way the
  // surface and the persistence agree (analyze_grid's self-check).
  fs::path d = temp_dir("diagonal");
  write_scalar_volume(sphere_with_bridge(40, 41), (d / "up.nii").string());
  write_scalar_volume(sphere_with_bridge(41, 40), (d / "down.nii").string());
  VolumeAnalysis up = analyze_file((d / "up.nii").string(), label(1));
  VolumeAnalysis down = analyze_file((d / "down.nii").string(), label(1));
  EXPECT_EQ(up.result.surface_stats.genus, 1);
  EXPECT_EQ(up.result.chokes.handle_generators, 1);
  EXPECT_EQ(down.result.surface_stats.genus, 0);
  EXPECT_EQ(down.result.chokes.handle_generators, 0);
  fs::remove_all(d);
}

TEST(VolumeWorld, ObliqueSformAnisotropicSpacingLoopsAtKnownWorldPositions) {
  fs::path d = temp_dir("oblique");
  const std::array<double, 3> h{0.7, 1.0, 1.5};
  const ObliqueTorus ot = oblique_torus();
  const auto& Rm = ot.rotation;
  const auto& centre_world = ot.centre_world;
  auto img = ot.image;
  write_scalar_volume(img, (d / "oblique.nii.gz").string());
  VolumeImage in = read_volume((d / "oblique.nii.gz").string());
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(in.spacing[a], h[a], 1e-5);
  EXPECT_EQ(in.transform_source, "sform");
  VolumeAnalysis a = analyze_volume(in, label(1), {});
  const AnalyzeResult& r = a.result;
  const auto [hl, tl] = test::expect_torus_generator_loops(r, centre_world, 12, 5);
  ASSERT_TRUE(hl && tl);
  // The handle loop's plane contains the torus axis: its normal is perpendicular to the rotated z axis.
  const auto nrm = r.frame.rotate(hl->normal);
  EXPECT_LT(std::abs(nrm[0] * Rm[0][2] + nrm[1] * Rm[1][2] + nrm[2] * Rm[2][2]), 0.2);
  // Every written point inside the image's world box (back through the inverse affine).
  write_report(r, {}, (d / "out").string());
  auto names = write_loop_volumes(a, in, (d / "out").string()).files;
  nlohmann::json j;
  std::ifstream((d / "out" / "loops.json")) >> j;
  EXPECT_EQ(j["coordinates"]["convention"], "RAS");
  EXPECT_EQ(j["units"], "mm");
  EXPECT_EQ(j["volume"]["dims"][0], 64);  // the volume's own fields, merged into loops.json
  EXPECT_NEAR(j["volume"]["spacing_mm"][2].get<double>(), 1.5, 1e-5);
  Eigen::Matrix4d A = Eigen::Matrix4d::Identity();
  for (int q = 0; q < 3; ++q)
    for (int c2 = 0; c2 < 4; ++c2) A(q, c2) = in.affine[q][c2];
  Eigen::Matrix4d Ainv = A.inverse();
  int points = 0;
  for (auto& l : j["loops"])
    for (auto& p : l["points"]) {
      Eigen::Vector4d ijk = Ainv * Eigen::Vector4d(p[0].get<double>(), p[1].get<double>(), p[2].get<double>(), 1);
      for (int q = 0; q < 3; ++q) {
        EXPECT_GE(ijk[q], -0.5);
        EXPECT_LE(ijk[q], in.dims[q] - 0.5);
      }
      ++points;
    }
  EXPECT_GT(points, 20);
  const auto& jt = j["loops"][int(tl - r.loops.data())]["centroid"];
  EXPECT_LT(dist({jt[0].get<double>(), jt[1].get<double>(), jt[2].get<double>()}, centre_world), 1.0);
  // The loop label volume: the input's grid and transform, each loop's voxels carrying its id + 1.
  VolumeImage lv = read_volume((d / "out" / names[0]).string());
  EXPECT_EQ(lv.dims, in.dims);
  for (int q = 0; q < 3; ++q)
    for (int c2 = 0; c2 < 4; ++c2) EXPECT_NEAR(lv.affine[q][c2], in.affine[q][c2], 1e-4);
  int tunnel_voxels = 0, tid = int(tl - r.loops.data()) + 1;
  double sx = 0, sy = 0, sz = 0;
  for (int k = 0; k < lv.dims[2]; ++k)
    for (int jj = 0; jj < lv.dims[1]; ++jj)
      for (int i = 0; i < lv.dims[0]; ++i)
        if (lv.values[std::size_t(i) + std::size_t(lv.dims[0]) * (jj + std::size_t(lv.dims[1]) * k)] == tid) {
          auto w = lv.to_world(i, jj, k);
          sx += w[0], sy += w[1], sz += w[2];
          ++tunnel_voxels;
        }
  ASSERT_GT(tunnel_voxels, 10);
  EXPECT_LT(dist({sx / tunnel_voxels, sy / tunnel_voxels, sz / tunnel_voxels}, centre_world), 1.5);
  fs::remove_all(d);
}

// --voxel-size resamples onto an isotropic lattice along the image's axes: the loops stay where the
// anisotropic analysis puts them in world mm, the label volumes stay on the input's own grid, and a mask's
// boundary still runs halfway between its voxels (the inside volume is kept).
TEST(VolumeWorld, ResampledToIsotropicVoxelsKeepsWorldPositions) {
  fs::path d = temp_dir("resampled");
  const ObliqueTorus ot = oblique_torus();
  VolumeFieldOptions f = label(1);
  f.voxel_size = 0.5;
  VolumeAnalysis a = analyze_volume(ot.image, f, {});
  const AnalyzeResult& r = a.result;
  for (int c = 0; c < 3; ++c) EXPECT_DOUBLE_EQ(r.grid.h(c), 0.5);
  EXPECT_EQ(r.surface_stats.genus, 1);
  const auto [hl, tl] = test::expect_torus_generator_loops(r, ot.centre_world, 12, 5);
  ASSERT_TRUE(hl && tl);
  // The inside volume: the resampled mask's voxels (0.125 mm^3) against the input's (1.05 mm^3).
  const VolumeAnalysis native = analyze_volume(ot.image, label(1), {});
  const double v_native = 0.7 * 1.0 * 1.5;
  std::size_t in_native = 0, in_resampled = 0;
  for (float x : native.result.grid.values) in_native += x < 0;
  for (float x : r.grid.values) in_resampled += x < 0;
  EXPECT_NEAR(0.125 * double(in_resampled), v_native * double(in_native), 0.05 * v_native * double(in_native));
  fs::create_directories(d);
  const LoopVolumes volumes = write_loop_volumes(a, ot.image, d.string());
  EXPECT_TRUE(volumes.warnings.empty());
  // The loop volume is on the input's grid; the tunnel loop's voxels circle the torus centre.
  const VolumeImage lv = read_volume((d / volumes.files[0]).string());
  EXPECT_EQ(lv.dims, ot.image.dims);
  const int tid = int(tl - r.loops.data()) + 1;
  double sum[3] = {0, 0, 0};
  int n = 0;
  for (int k = 0; k < lv.dims[2]; ++k)
    for (int j = 0; j < lv.dims[1]; ++j)
      for (int i = 0; i < lv.dims[0]; ++i)
        if (lv.values[std::size_t(i) + std::size_t(lv.dims[0]) * (j + std::size_t(lv.dims[1]) * k)] == tid) {
          const auto w = ot.image.to_world(i, j, k);
          for (int c = 0; c < 3; ++c) sum[c] += w[c];
          ++n;
        }
  ASSERT_GT(n, 10);
  EXPECT_LT(dist({sum[0] / n, sum[1] / n, sum[2] / n}, ot.centre_world), 1.5);
  // Too fine a lattice for the memory budget is refused before allocating.
  f.voxel_size = 1e-4;
  try {
    analyze_volume(ot.image, f, {});
    ADD_FAILURE() << "a 1e-4 mm lattice was not refused";
  } catch (const Error& e) {
    EXPECT_EQ(e.exit_code, 3) << e.what();
  }
  fs::remove_all(d);
}

// membranes.nii.gz means what it says: flipping one loop's membrane voxels in the mask removes that loop's
// handle (cut) or tunnel (fill), and nothing else: genus 1 -> 0, one surface component, no cavity.
TEST(VolumeWorld, MembraneVolumeCutsTheHandleAndFillsTheTunnel) {
  fs::path d = temp_dir("membranes");
  const std::array<double, 3> c{22, 24, 21};
  auto img = make_image({64, 48, 29}, {0.7, 1.0, 1.5}, "uint8", [&](double x, double y, double z) { return torus(x, y, z, c, 12, 5); });
  write_scalar_volume(img, (d / "torus.nii.gz").string());
  VolumeImage in = read_volume((d / "torus.nii.gz").string());
  VolumeAnalysis a = analyze_volume(in, label(1), {});
  const AnalyzeResult& r = a.result;
  ASSERT_EQ(r.surface_stats.genus, 1);
  const Loop* hl = find_loop(r, Side::Handle, Kind::Generator);
  const Loop* tl = find_loop(r, Side::Tunnel, Kind::Generator);
  ASSERT_TRUE(hl && tl);
  fs::create_directories(d / "out");
  const LoopVolumes volumes = write_loop_volumes(a, in, (d / "out").string());
  EXPECT_TRUE(volumes.warnings.empty());
  const auto& names = volumes.files;
  const VolumeImage mv = read_volume((d / "out" / names[1]).string());
  ASSERT_EQ(mv.dims, in.dims);
  for (const Loop* l : {hl, tl}) {
    const int id = int(l - r.loops.data()) + 1;
    const float inside = l == hl ? 1.f : 0.f;
    VolumeImage edited = in;
    int voxels = 0;
    for (std::size_t v = 0; v < mv.values.size(); ++v)
      if (mv.values[v] == id) {
        EXPECT_EQ(in.values[v], inside) << "a membrane voxel on the wrong side at " << v;
        edited.values[v] = 1.f - inside;
        ++voxels;
      }
    // A disc across the tube (r 5 mm, at most ~2 voxels thick) or across the hole (r 7 mm, the same).
    EXPECT_GT(voxels, 20);
    EXPECT_LT(voxels, l == hl ? 400 : 700);
    const AnalyzeResult after = analyze_volume(edited, label(1), {}).result;
    EXPECT_EQ(after.surface_stats.genus, 0) << (l == hl ? "handle" : "tunnel");
    EXPECT_EQ(after.surface_stats.components, 1);
    EXPECT_EQ(after.chokes.handle_generators, 0);
  }
  // Watched, the label volumes report their loops' membranes as they finish and write the same files; asked
  // to stop, they write none.
  std::vector<double> fractions;
  fs::create_directories(d / "watched");
  write_loop_volumes(a, in, (d / "watched").string(), [&](const char* stage, double f) {
    EXPECT_STREQ(stage, "label volumes");
    fractions.push_back(f);
    return true;
  });
  ASSERT_GE(fractions.size(), 2u);
  EXPECT_EQ(fractions.front(), 0.0);
  EXPECT_EQ(fractions.back(), 1.0);
  EXPECT_TRUE(std::is_sorted(fractions.begin(), fractions.end()));
  for (const auto& name : names) {
    std::ifstream x(d / "out" / name, std::ios::binary), y(d / "watched" / name, std::ios::binary);
    EXPECT_TRUE(std::equal(std::istreambuf_iterator<char>(x), {}, std::istreambuf_iterator<char>(y), {})) << name;
  }
  fs::create_directories(d / "stopped");
  try {
    write_loop_volumes(a, in, (d / "stopped").string(), [](const char*, double f) { return f == 0; });
    ADD_FAILURE() << "not interrupted";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "interrupted");
  }
  EXPECT_TRUE(fs::is_empty(d / "stopped"));
  fs::remove_all(d);
}

TEST(VolumeWorld, NrrdKeepsItsSpaceAndValues) {
  fs::path d = temp_dir("nrrd");
  auto img = make_image({20, 22, 24}, {0.5, 1, 2}, "int16", [](double x, double y, double z) { return float(x + 10 * y - z); });
  img.convention = "LPS";
  img.affine[0][3] = 5;
  img.affine[1][3] = -7;
  write_scalar_volume(img, (d / "v.nrrd").string());
  VolumeImage in = read_volume((d / "v.nrrd").string());
  EXPECT_EQ(in.convention, "LPS");
  EXPECT_EQ(in.dims, img.dims);
  EXPECT_EQ(in.datatype, "int16");
  for (std::size_t i = 0; i < img.values.size(); i += 97) EXPECT_EQ(in.values[i], float(std::int16_t(img.values[i])));
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) EXPECT_DOUBLE_EQ(in.affine[r][c], img.affine[r][c]);
  fs::remove_all(d);
}

namespace {
void expect_bad(const std::function<void()>& f, const std::string& needle) {
  try {
    f();
    ADD_FAILURE() << "no error; expected one naming '" << needle << "'";
  } catch (const Error& e) {
    EXPECT_EQ(e.exit_code, 2);
    const std::string m = e.what();
    EXPECT_NE(m.find(needle), std::string::npos) << m;
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
  }
}
}  // namespace

TEST(VolumeBadInput, OneLineErrorsWithExitCode2) {
  fs::path d = temp_dir("bad");
  auto img = make_image({16, 16, 16}, {1, 1, 1}, "uint8", [](double x, double, double) { return x > 5 ? 1.f : 0.f; });
  // truncated gz
  write_scalar_volume(img, (d / "t.nii.gz").string());
  fs::resize_file(d / "t.nii.gz", fs::file_size(d / "t.nii.gz") / 2);
  expect_bad([&] { read_volume((d / "t.nii.gz").string()); }, "t.nii.gz");
  // truncated data (uncompressed): the header promises more voxels than the file has
  write_scalar_volume(img, (d / "short.nii").string());
  fs::resize_file(d / "short.nii", fs::file_size(d / "short.nii") - 100);
  expect_bad([&] { read_volume((d / "short.nii").string()); }, "short.nii");
  // wrong dims: a single slice
  auto flat = make_image({16, 16, 1}, {1, 1, 1}, "uint8", [](double, double, double) { return 1.f; });
  write_scalar_volume(flat, (d / "flat.nii").string());
  expect_bad([&] { read_volume((d / "flat.nii").string()); }, "dims");
  // empty label
  write_scalar_volume(img, (d / "ok.nii").string());
  expect_bad([&] { analyze_file((d / "ok.nii").string(), label(7)); }, "label 7");
  // NaN
  auto nan = make_image({8, 8, 8}, {1, 1, 1}, "float32", [](double x, double, double) { return x == 3 ? NAN : 1.f; });
  write_scalar_volume(nan, (d / "nan.nii").string());
  expect_bad([&] { read_volume((d / "nan.nii").string()); }, "NaN");
  // unsupported datatype (complex)
  {
    const int64_t dims[8] = {3, 8, 8, 8, 1, 1, 1, 1};
    nifti_image* c = nifti_make_new_nim(dims, DT_COMPLEX64, 1);
    nifti_set_filenames(c, (d / "complex.nii").c_str(), 0, 1);
    nifti_image_write(c);
    nifti_image_free(c);
  }
  expect_bad([&] { read_volume((d / "complex.nii").string()); }, "datatype");
  // 4D without --volume, and with one
  {
    const int64_t dims[8] = {4, 8, 8, 8, 3, 1, 1, 1};
    nifti_image* c = nifti_make_new_nim(dims, DT_UINT8, 1);
    nifti_set_filenames(c, (d / "4d.nii").c_str(), 0, 1);
    nifti_image_write(c);
    nifti_image_free(c);
  }
  expect_bad([&] { read_volume((d / "4d.nii").string()); }, "--volume");
  EXPECT_EQ(read_volume((d / "4d.nii").string(), 2).volume, 2);
  // no such file
  expect_bad([&] { read_volume((d / "missing.nii.gz").string()); }, "no such file");
  // the CLI: exit code 2 and one line on stderr
  auto cli = [&](const std::string& input, const std::string& args, std::string& stderr_text) {
    const std::string err = (d / "err.txt").string();
    const int status = std::system((std::string("'") + CHOKELOOPS_CLI + "' analyze '" + (d / input).string() + "' " + args +
                                    " -o '" + (d / "o").string() + "' --quiet 2>'" + err + "' >/dev/null")
                                       .c_str());
    std::ifstream e(err);
    stderr_text.assign(std::istreambuf_iterator<char>(e), std::istreambuf_iterator<char>());
    return WEXITSTATUS(status);
  };
  std::string all;
  EXPECT_EQ(cli("t.nii.gz", "--label 1", all), 2);
  EXPECT_EQ(std::count(all.begin(), all.end(), '\n'), 1) << all;
  // a volume keeps its own lattice unless --voxel-size resamples it: --resolution is refused
  EXPECT_EQ(cli("ok.nii", "--label 1 --resolution 64", all), 2);
  EXPECT_EQ(std::count(all.begin(), all.end(), '\n'), 1) << all;
  EXPECT_NE(all.find("--voxel-size"), std::string::npos) << all;
  EXPECT_EQ(cli("ok.nii", "--label 1 --voxel-size 0.5", all), 0) << all;
  nlohmann::json j;
  std::ifstream(d / "o" / "loops.json") >> j;
  EXPECT_EQ(j["volume"]["resampled_to_mm"], 0.5);
  fs::remove_all(d);
}

// The MNI GM probability map (uint8 0-255) at 128: 882 handles, 87 of them born exactly at 0 in the raw field. Given as a raw field
// (128 - value: exact zeros wherever a voxel is exactly at the iso value) the self-check failed before the
// chokes took the solid as {phi <= 0} like the surface does; through the volume path (no zeros) too.
TEST(VolumeMni, GreyMatterMapSurfaceGenusEqualsHandleGenerators) {
  const std::string path = std::string(CHOKELOOPS_DATA) + "/volumes/mni_icbm152_gm_tal_nlin_sym_09a_converted.nii.gz";
  VolumeImage img = read_volume(path);
  EXPECT_EQ(img.convention, "RAS");
  AnalyzeOptions o;
  o.max_loops = 4;
  o.check_generators = false;
  {
    ScalarGrid g;
    const int pad = 2;
    for (int a = 0; a < 3; ++a) g.dims[a] = img.dims[a] + 2 * pad;
    g.values.assign(std::size_t(g.vertex_count()), 1.f);
    std::size_t zeros = 0;
    for (int k = 0; k < img.dims[2]; ++k)
      for (int j = 0; j < img.dims[1]; ++j)
        for (int i = 0; i < img.dims[0]; ++i) {
          float v = 128.f - img.values[std::size_t(i) + std::size_t(img.dims[0]) * (j + std::size_t(img.dims[1]) * k)];
          zeros += v == 0;
          g.values[std::size_t(g.index(i + pad, j + pad, k + pad))] = v;
        }
    EXPECT_GT(zeros, 1000u);
    AnalyzeResult r = analyze_grid(std::move(g), o);  // throws InternalError on a mismatch
    EXPECT_EQ(r.surface_stats.genus, r.chokes.handle_generators);
    // The handles born exactly at 0, which a strict `birth < 0` missed while the surface has them.
    int born_at_zero = 0;
    for (auto& p : r.diagram.pairs) born_at_zero += p.dim == 1 && p.birth == 0 && p.death > 0;
    EXPECT_GT(born_at_zero, 0);
    std::printf("raw GM field: %d handle generators, %d of them born exactly at 0\n", r.chokes.handle_generators, born_at_zero);
    EXPECT_GT(r.chokes.handle_generators, 500);
  }
  VolumeFieldOptions f;
  f.has_iso = true;
  f.iso = 128;
  VolumeAnalysis a = analyze_volume(img, f, o);
  const AnalyzeResult& r = a.result;
  EXPECT_TRUE(r.surface_stats.closed_manifold);
  EXPECT_EQ(r.surface_stats.genus, r.chokes.handle_generators);
  EXPECT_GT(r.chokes.handle_generators, 500);
  EXPECT_EQ(int(r.loops.size()), 4);
  EXPECT_GT(r.loops_omitted, 500);
  // most persistent first
  for (std::size_t i = 1; i < r.loops.size(); ++i)
    EXPECT_GE(r.loops[i - 1].choke.death - r.loops[i - 1].choke.birth, r.loops[i].choke.death - r.loops[i].choke.birth);
}

// Found by fuzzing: a NIfTI header promising far more voxels than its file holds was allocated before the read
// failed. It is refused from the file's size, plain or gzipped, before any allocation.
TEST(VolumeBadInput, HeaderPromisingMoreThanTheFileHoldsIsRefusedBeforeAllocating) {
  std::ifstream in(std::string(CHOKELOOPS_SOURCE_DIR) + "/fuzz/corpus/nii/box.nii", std::ios::binary);
  std::string nii((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_EQ(nii.size(), 472u);
  const std::int16_t dims[4] = {3, 30000, 30000, 30000};  // 2.7e13 bytes of uint8
  std::memcpy(&nii[40], dims, sizeof dims);
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("chokeloops_huge_" + std::to_string(::getpid()) + ".nii")).string();
  std::ofstream(path, std::ios::binary) << nii;
  try {
    chokeloops::read_volume(path);
    ADD_FAILURE() << "a 30000^3 header on a 472-byte file was accepted";
  } catch (const chokeloops::Error& e) {
    EXPECT_EQ(e.exit_code, 2);
    EXPECT_NE(std::string(e.what()).find("shorter than"), std::string::npos) << e.what();
  }
  std::filesystem::remove(path);
}

// Found by fuzzing (a timeout): a 350-byte .nii whose vox_offset is NaN (niftilib makes it -2^31) let its
// 1286x256x1024 float32 volume (1.3 GB) "fit" in the file; it was allocated before the read failed. A negative
// offset, or a data file that cannot be sized, is now refused first, with exit code 2 and one line.
TEST(VolumeBadInput, FuzzNegativeDataOffsetIsRefusedBeforeAllocating) {
  std::ifstream in(std::string(CHOKELOOPS_SOURCE_DIR) + "/fuzz/corpus/nii/regression-9bb633233cd8", std::ios::binary);
  std::string nii((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_EQ(nii.size(), 350u);
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("chokeloops_noimg_" + std::to_string(::getpid()) + ".nii")).string();
  std::ofstream(path, std::ios::binary) << nii;
  try {
    chokeloops::read_volume(path);
    ADD_FAILURE() << "a header without its data file was accepted";
  } catch (const chokeloops::Error& e) {
    EXPECT_EQ(e.exit_code, 2);
    const std::string m = e.what();
    // (-2^31 is what x86 makes of NaN; elsewhere the offset may be 0, and then the size check refuses it). Both
    // refusals come before any voxel is allocated: no clock is needed to tell.
    EXPECT_TRUE(m.find("vox_offset") != std::string::npos || m.find("shorter than") != std::string::npos) << m;
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
  }
  std::filesystem::remove(path);
}

// Generators thinner than a voxel on a flat core (pinholes and hair-thin bridges of the raw map): their
// interface curves are contractible in every box, and the floods that went on to the whole grid closed loops
// thousands of voxels long around a hole a fraction of a voxel wide. From a box of kThinCoreBox voxels they
// take the plane sections first. On this 128-voxel crop of the GM map two of them went from 2810 and 3570
// voxels to section loops of ~3.
TEST(VolumeMni, GeneratorsThinnerThanAVoxelGetLocalLoops) {
  const std::string path = std::string(CHOKELOOPS_DATA) + "/volumes/mni_icbm152_gm_tal_nlin_sym_09a_converted.nii.gz";
  const VolumeImage img = read_volume(path);
  const int centre[3] = {111, 95, 58}, half = 64, pad = 2;
  ScalarGrid g;
  for (int a = 0; a < 3; ++a) g.dims[a] = 2 * half + 2 * pad;
  g.values.assign(std::size_t(g.vertex_count()), 1.f);
  for (int k = 0; k < 2 * half; ++k)
    for (int j = 0; j < 2 * half; ++j)
      for (int i = 0; i < 2 * half; ++i) {
        const int q[3] = {centre[0] - half + i, centre[1] - half + j, centre[2] - half + k};
        bool inside = true;
        for (int a = 0; a < 3; ++a) inside = inside && q[a] >= 0 && q[a] < img.dims[a];
        if (inside)
          g.values[std::size_t(g.index(i + pad, j + pad, k + pad))] =
              128.f - img.values[std::size_t(q[0]) + std::size_t(img.dims[0]) * (q[1] + std::size_t(img.dims[1]) * std::size_t(q[2]))];
      }
  AnalyzeOptions o;
  o.max_loops = -1;
  const AnalyzeResult r = analyze_grid(std::move(g), o);
  EXPECT_EQ(r.surface_stats.genus, r.chokes.handle_generators);
  int thin = 0, local = 0, sections = 0, short_sections = 0, over_1000 = 0;
  for (const Loop& l : r.loops) {
    if (l.choke.kind != Kind::Generator || l.choke.depth >= r.grid.voxel_size || !l.found) continue;
    ++thin;
    local += l.length < 20 * r.grid.voxel_size;
    const bool section = l.note.find("plane section") != std::string::npos;
    sections += section;
    short_sections += section && l.length < 20 * r.grid.voxel_size;
    over_1000 += l.length > 1000 * r.grid.voxel_size;
  }
  std::printf("GM crop: genus %d, %zu loops, %d generators thinner than a voxel with a loop, %d of them shorter than 20 "
              "voxels, %d plane sections (%d shorter than 20 voxels), %d longer than 1000 voxels\n",
              r.surface_stats.genus, r.loops.size(), thin, local, sections, short_sections, over_1000);
  // A handle thinner than a voxel has a loop of a few voxels at most: the membrane's rim (taken along one
  // side of the interface, edge by edge) gave 60 of 60 such loops, where snapping the rim's points to their
  // nearest vertices had collapsed the smallest rims and left 10 of 59 to longer loops (6 over 100 voxels).
  EXPECT_GT(thin, 40);
  EXPECT_GE(local, thin - 2);
  EXPECT_GE(sections, 10);
  EXPECT_EQ(short_sections, sections);
  EXPECT_EQ(over_1000, 0);
}

// The label volume's membranes are `chokeloops filter`'s edits: each stays within the widest box the filter
// lets a membrane grow to around its choke (membrane_box_cap). On the grey-matter map the sheets of sub-voxel
// tunnels that closed only in boxes past it spread over thousands of voxels of cortex and hid other loops'
// membranes (labels are written in turn); where the sheet does not close in that box the plane does, or the
// loop is listed without membrane voxels. A 96-voxel crop of the map at 1 mm, iso 128, every loop.
TEST(VolumeMni, LabelVolumeMembranesStayInTheFiltersBoxes) {
  const std::string path = std::string(CHOKELOOPS_DATA) + "/volumes/mni_icbm152_gm_tal_nlin_sym_09a_converted.nii.gz";
  const VolumeImage full = read_volume(path);
  const int corner[3] = {60, 60, 40}, n = 96;
  const fs::path d = temp_dir("mni_membranes");
  VolumeImage crop = make_image({n, n, n}, {1, 1, 1}, "float32", [&](double x, double y, double z) {
    const int q[3] = {corner[0] + int(x), corner[1] + int(y), corner[2] + int(z)};
    for (int a = 0; a < 3; ++a)
      if (q[a] >= full.dims[a]) return 0.f;
    return full.values[std::size_t(q[0]) + std::size_t(full.dims[0]) * (std::size_t(q[1]) + std::size_t(full.dims[1]) * std::size_t(q[2]))];
  });
  write_scalar_volume(crop, (d / "crop.nii.gz").string());
  const VolumeImage in = read_volume((d / "crop.nii.gz").string());
  VolumeFieldOptions f;
  f.has_iso = true;
  f.iso = 128;
  AnalyzeOptions o;
  o.max_loops = -1;
  const VolumeAnalysis a = analyze_volume(in, f, o);
  const AnalyzeResult& r = a.result;
  fs::create_directories(d / "out");
  const LoopVolumes volumes = write_loop_volumes(a, in, (d / "out").string());
  const VolumeImage mv = read_volume((d / "out" / volumes.files[1]).string());
  ASSERT_EQ(mv.dims, in.dims);
  // Each label's farthest voxel from its choke's saddle (in voxels, along an axis).
  std::vector<int> reach(r.loops.size() + 1, -1);
  std::vector<std::array<int, 3>> saddle(r.loops.size());
  const FreudenthalComplex cx(r.grid.dims);
  for (std::size_t i = 0; i < r.loops.size(); ++i) {
    const auto p = cx.coords(r.loops[i].choke.saddle);
    for (int c = 0; c < 3; ++c) saddle[i][std::size_t(c)] = int(std::lround(r.grid.origin[c] + p[c] * r.grid.h(c)));
  }
  int labels = 0;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const int id = int(mv.values[std::size_t(i) + std::size_t(n) * (std::size_t(j) + std::size_t(n) * std::size_t(k))]);
        if (id <= 0) continue;
        ASSERT_LE(id, int(r.loops.size()));
        const auto& s = saddle[std::size_t(id - 1)];
        labels += reach[std::size_t(id)] < 0;
        reach[std::size_t(id)] = std::max({reach[std::size_t(id)], std::abs(i - s[0]), std::abs(j - s[1]), std::abs(k - s[2])});
      }
  int widest = 0;
  for (std::size_t i = 0; i < r.loops.size(); ++i) {
    if (reach[i + 1] < 0) continue;
    const int cap = membrane_box_cap(r.grid, r.loops[i].choke, LoopOptions{}, true);
    EXPECT_LE(reach[i + 1], cap + 1) << "loop " << i << " depth " << r.loops[i].choke.depth;
    widest = std::max(widest, reach[i + 1]);
  }
  std::printf("GM crop: %zu loops, %d membranes in the label volume, farthest voxel %d from its saddle, %zu warnings\n",
              r.loops.size(), labels, widest, volumes.warnings.size());
  EXPECT_GT(labels, 50);
  fs::remove_all(d);
}
