// Round trips and error messages of the .vdb IO (stage levelset).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>

#include <openvdb/io/Compression.h>
#include <openvdb/io/File.h>
#include <openvdb/tools/LevelSetSphere.h>

#include "chokeloops/io/vdb_io.h"
#include "temp_dir.h"

using namespace chokeloops;
namespace fs = std::filesystem;

namespace {
fs::path temp_dir(const std::string& name) { return test::temp_dir("vdbio_" + name); }

template <class F>
std::string error_of(F&& f, int* code = nullptr) {
  try {
    f();
  } catch (const Error& e) {
    if (code) *code = e.exit_code;
    return e.what();
  }
  return "";
}
}  // namespace

TEST(VdbIo, RoundTripExact) {
  ScalarGrid g;
  g.dims = {5, 4, 3};
  g.origin = {-1.5, 0.25, 3.0};
  g.voxel_size = 0.125;
  g.values.resize(g.vertex_count());
  for (std::size_t i = 0; i < g.values.size(); ++i) g.values[i] = float(i) * 0.01f - 0.3f;
  g.values[7] = 0.0f;  // zero is a legal value
  auto dir = temp_dir("roundtrip");
  auto path = (dir / "g.vdb").string();
  write_vdb(g, path);
  ScalarGrid r = read_vdb_dense(path);
  EXPECT_EQ(r.dims, g.dims);
  EXPECT_DOUBLE_EQ(r.voxel_size, g.voxel_size);
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(r.origin[a], g.origin[a], 1e-12);
  ASSERT_EQ(r.values.size(), g.values.size());
  for (std::size_t i = 0; i < g.values.size(); ++i) EXPECT_EQ(r.values[i], g.values[i]) << i;
  auto grids = list_vdb_grids(path);
  ASSERT_EQ(grids.size(), 1u);
  EXPECT_EQ(grids[0].name, "sdf");
  EXPECT_EQ(grids[0].type, "float");
  fs::remove_all(dir);
}

TEST(VdbIo, NarrowBandSphereKeepsSignInside) {
  ensure_openvdb_initialized();
  auto sphere = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(1.0f, openvdb::Vec3f(0.5f, 0, 0), 0.05f, 3.f);
  sphere->setName("ball");
  auto dir = temp_dir("sphere");
  auto path = (dir / "s.vdb").string();
  openvdb::io::File(path).write({sphere});
  ScalarGrid r = read_vdb_dense(path, "ball");
  EXPECT_NEAR(r.voxel_size, 0.05, 1e-8);
  // bbox of the narrow band: about [-0.65, 1.65] in x
  EXPECT_NEAR(r.origin[0], 0.5 - 1.0 - 3 * 0.05, 0.051);
  // centre vertex is deep inside: -background
  int ci = int(std::lround((0.5 - r.origin[0]) / r.voxel_size));
  int cj = int(std::lround((0.0 - r.origin[1]) / r.voxel_size));
  int ck = int(std::lround((0.0 - r.origin[2]) / r.voxel_size));
  EXPECT_LT(r.values[r.index(ci, cj, ck)], 0.f);
  EXPECT_GT(r.values[r.index(0, 0, 0)], 0.f);  // corner of the box is outside
  fs::remove_all(dir);
}

TEST(VdbIo, Errors) {
  auto dir = temp_dir("errors");
  int code = 0;
  std::string m = error_of([&] { read_vdb_dense((dir / "missing.vdb").string()); }, &code);
  EXPECT_NE(m.find("missing.vdb"), std::string::npos) << m;
  EXPECT_NE(m.find("no such file"), std::string::npos) << m;
  EXPECT_EQ(code, 2);
  m = error_of([&] { read_vdb_dense(dir.string()); });
  EXPECT_NE(m.find("directory"), std::string::npos) << m;
  { std::ofstream(dir / "text.vdb") << "hello, not a vdb\n"; }
  m = error_of([&] { read_vdb_dense((dir / "text.vdb").string()); });
  EXPECT_NE(m.find("text.vdb"), std::string::npos) << m;
  EXPECT_NE(m.find("not a readable VDB"), std::string::npos) << m;
  { std::ofstream(dir / "empty.vdb"); }
  m = error_of([&] { read_vdb_dense((dir / "empty.vdb").string()); });
  EXPECT_NE(m.find("empty"), std::string::npos) << m;

  ensure_openvdb_initialized();
  auto vg = openvdb::Vec3SGrid::create();
  vg->setName("velocity");
  vg->tree().setValue(openvdb::Coord(1, 2, 3), openvdb::Vec3s(1, 0, 0));
  openvdb::io::File((dir / "vec.vdb").string()).write({vg});
  m = error_of([&] { read_vdb_dense((dir / "vec.vdb").string()); });
  EXPECT_NE(m.find("no float grid"), std::string::npos) << m;
  EXPECT_NE(m.find("'velocity' (vec3s)"), std::string::npos) << m;

  auto fg = openvdb::FloatGrid::create(1.f);
  fg->setName("empty");
  openvdb::io::File((dir / "emptygrid.vdb").string()).write({fg});
  m = error_of([&] { read_vdb_dense((dir / "emptygrid.vdb").string()); });
  EXPECT_NE(m.find("is empty"), std::string::npos) << m;

  auto ng = openvdb::FloatGrid::create(1.f);
  ng->tree().setValue(openvdb::Coord(0, 0, 0), std::nanf(""));
  ng->tree().setValue(openvdb::Coord(1, 0, 0), 0.5f);
  openvdb::io::File((dir / "nan.vdb").string()).write({ng});
  m = error_of([&] { read_vdb_dense((dir / "nan.vdb").string()); });
  EXPECT_NE(m.find("non-finite"), std::string::npos) << m;

  auto sg = openvdb::FloatGrid::create(1.f);
  sg->tree().setValue(openvdb::Coord(0, 0, 0), 0.5f);
  sg->setTransform(openvdb::math::Transform::createLinearTransform(openvdb::Mat4R(
      openvdb::Mat4R(1, 0, 0, 0, 0, 2, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1))));
  openvdb::io::File((dir / "aniso.vdb").string()).write({sg});
  m = error_of([&] { read_vdb_dense((dir / "aniso.vdb").string()); });
  EXPECT_NE(m.find("uniform"), std::string::npos) << m;
  for (auto& s : {m}) EXPECT_EQ(s.find('\n'), std::string::npos);
  fs::remove_all(dir);
}

// Every value block of a .vdb file goes through the guard of src/io/vdb_guard.cpp. Files written by OpenVDB with
// each compression it has (none, zlib, blosc, with and without active-mask compression, values as half floats)
// come back exactly: every leaf value, active or not, and every active tile. The grid read is the second of two.
TEST(VdbIo, EveryCompressionReadsBackExactlyThroughTheGuard) {
  ensure_openvdb_initialized();
  auto dir = temp_dir("compression");
  const std::uint32_t zip = openvdb::io::COMPRESS_ZIP, blosc = openvdb::io::COMPRESS_BLOSC,
                      mask = openvdb::io::COMPRESS_ACTIVE_MASK;
  for (std::uint32_t c : {0u, zip, blosc, mask, zip | mask, blosc | mask}) {
    for (bool half : {false, true}) {
      auto sphere = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(1.0f, openvdb::Vec3f(0.1f, 0, 0), 0.05f);
      sphere->setName("ball");
      sphere->setSaveFloatAsHalf(half);
      sphere->tree().addTile(1, openvdb::Coord(512, 0, 0), -0.5f, true);  // an active tile in an internal node
      // eight leaves: OpenVDB pads its delayed-load table of 8 x 8 bytes to 128 before blosc compresses it
      auto other = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(2.0f, openvdb::Vec3f(0, 0, 0), 0.5f);
      other->setName("first");
      const std::string what = "compression " + std::to_string(c) + (half ? " half" : " float");
      const auto path = (dir / ("c" + std::to_string(c) + (half ? "h" : "f") + ".vdb")).string();
      openvdb::io::File file(path);
      file.setCompression(c);
      file.write({other, sphere});
      EXPECT_EQ(read_vdb_float_grid(path, "first")->activeVoxelCount(), other->activeVoxelCount()) << what;
      auto back = read_vdb_float_grid(path, "ball");
      ASSERT_EQ(back->activeVoxelCount(), sphere->activeVoxelCount()) << what;
      ASSERT_EQ(back->tree().leafCount(), sphere->tree().leafCount()) << what;
      auto expect = [&](float v) { return half ? openvdb::io::truncateRealToHalf(v) : v; };
      std::size_t differ = 0;
      for (auto leaf = sphere->tree().cbeginLeaf(); leaf; ++leaf) {
        const auto* got = back->tree().probeConstLeaf(leaf->origin());
        ASSERT_NE(got, nullptr) << what;
        for (openvdb::Index i = 0; i < leaf->SIZE; ++i)
          differ += got->getValue(i) != expect(leaf->getValue(i)) || got->isValueOn(i) != leaf->isValueOn(i);
      }
      EXPECT_EQ(differ, 0u) << what;
      EXPECT_EQ(sphere->tree().getValue(openvdb::Coord(515, 3, 3)), -0.5f);  // the tile's 8^3 voxels
      EXPECT_EQ(back->tree().getValue(openvdb::Coord(515, 3, 3)), expect(-0.5f)) << what;
      EXPECT_TRUE(back->tree().isValueOn(openvdb::Coord(515, 3, 3))) << what;
    }
  }
  fs::remove_all(dir);
}

#include "chokeloops/field/levelset.h"

TEST(LevelSetVdbInput, NarrowBandSphereIsExtendedToThePaddedBox) {
  ensure_openvdb_initialized();
  const float r = 1.0f, h = 0.05f;
  auto sphere = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(r, openvdb::Vec3f(0, 0, 0), h, 3.f);
  LevelSetOptions o;
  o.quiet = true;
  LevelSetResult res = levelset_from_vdb(sphere, o, "sphere");
  EXPECT_EQ(res.source, "vdb level set");
  const ScalarGrid& g = res.grid;
  // box = surface bbox (about ±1) padded by 10% of 2 = 0.2 → about ±1.2
  EXPECT_LE(g.origin[0], -1.15);
  EXPECT_GE(g.origin[0], -1.3);
  double worst = 0;
  std::size_t wrong_sign = 0;
  for (int k = 0; k < g.dims[2]; ++k)
    for (int j = 0; j < g.dims[1]; ++j)
      for (int i = 0; i < g.dims[0]; ++i) {
        auto x = g.world({i, j, k});
        double d = std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]) - r;
        double phi = g.values[g.index(i, j, k)];
        worst = std::max(worst, std::abs(phi - d));
        if (std::abs(d) > h && (phi < 0) != (d < 0)) ++wrong_sign;
      }
  std::printf("vdb narrow-band sphere extended by the feature transform: max error %.3f voxel\n", worst / h);
  EXPECT_EQ(wrong_sign, 0u);
  EXPECT_LE(worst, 1.0 * h);  // the level set's 1-voxel bar deep inside (fast sweeping, used before, gave 1.19)
}

TEST(LevelSetVdbInput, FogVolumeBecomesSignedDistanceAtIso) {
  ensure_openvdb_initialized();
  auto fog = openvdb::FloatGrid::create(0.f);
  fog->setTransform(openvdb::math::Transform::createLinearTransform(0.1));
  fog->setGridClass(openvdb::GRID_FOG_VOLUME);
  auto acc = fog->getAccessor();
  // density 1 inside the ball of radius 1.0, smooth ramp to 0 over [1.0, 1.4]
  for (int k = -16; k <= 16; ++k)
    for (int j = -16; j <= 16; ++j)
      for (int i = -16; i <= 16; ++i) {
        double rr = 0.1 * std::sqrt(double(i * i + j * j + k * k));
        double v = rr < 1.0 ? 1.0 : rr > 1.4 ? 0.0 : 1.0 - (rr - 1.0) / 0.4;
        if (v > 0) acc.setValue(openvdb::Coord(i, j, k), float(v));
      }
  LevelSetOptions o;
  o.quiet = true;
  o.iso = 0.5;  // surface at r = 1.2
  LevelSetResult res = levelset_from_vdb(fog, o, "fog");
  EXPECT_EQ(res.source, "vdb fog");
  const ScalarGrid& g = res.grid;
  double worst = 0;
  for (int k = 0; k < g.dims[2]; ++k)
    for (int j = 0; j < g.dims[1]; ++j)
      for (int i = 0; i < g.dims[0]; ++i) {
        auto x = g.world({i, j, k});
        double d = std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]) - 1.2;
        if (std::abs(d) < 0.3) worst = std::max(worst, std::abs(g.values[g.index(i, j, k)] - d));
      }
  std::printf("fog sphere: max error near the iso surface %.3f voxel\n", worst / 0.1);
  EXPECT_LE(worst, 0.1);
  EXPECT_GT(res.inside_voxels, 0u);
}

TEST(LevelSetVdbInput, NonDistanceLevelSetIsRedistanced) {
  // A sphere and a torus given by polynomials whose gradient is far from 1 (|grad| = 2r on the sphere): the
  // grid must become their signed distance, with the accuracy asked of meshes (0.5 voxel near
  // the surface, 1 voxel deep inside), and the zero level set must stay where the input put it.
  ensure_openvdb_initialized();
  struct Shape {
    const char* name;
    double (*poly)(double, double, double);
    double (*dist)(double, double, double);
  };
  const Shape shapes[] = {
      {"sphere r 0.8", [](double x, double y, double z) { return x * x + y * y + z * z - 0.64; },
       [](double x, double y, double z) { return std::sqrt(x * x + y * y + z * z) - 0.8; }},
      {"torus R 0.6 r 0.25",
       [](double x, double y, double z) {
         const double q = x * x + y * y + z * z + 0.36 - 0.0625;
         return q * q - 4 * 0.36 * (x * x + y * y);
       },
       [](double x, double y, double z) {
         const double a = std::sqrt(x * x + y * y) - 0.6;
         return std::sqrt(a * a + z * z) - 0.25;
       }},
  };
  const double h = 1.0 / 64;  // 128 voxels across [-1, 1]
  for (const Shape& sh : shapes) {
    auto grid = openvdb::FloatGrid::create(1.f);
    grid->setTransform(openvdb::math::Transform::createLinearTransform(h));
    auto acc = grid->getAccessor();
    for (int k = -64; k <= 64; ++k)
      for (int j = -64; j <= 64; ++j)
        for (int i = -64; i <= 64; ++i) acc.setValue(openvdb::Coord(i, j, k), float(sh.poly(i * h, j * h, k * h)));
    LevelSetOptions o;
    o.quiet = true;
    LevelSetResult res = levelset_from_vdb(grid, o, sh.name);
    ASSERT_EQ(res.source, "vdb level set (renormalised)") << sh.name;
    const ScalarGrid& g = res.grid;
    double near = 0, deep = 0;
    std::size_t flipped = 0;
    for (int k = 0; k < g.dims[2]; ++k)
      for (int j = 0; j < g.dims[1]; ++j)
        for (int i = 0; i < g.dims[0]; ++i) {
          auto x = g.world({i, j, k});
          const double d = sh.dist(x[0], x[1], x[2]);
          const double phi = g.values[g.index(i, j, k)];
          const double err = std::abs(phi - d);
          if (std::abs(d) <= 2 * h) near = std::max(near, err);
          else if (d < 0) deep = std::max(deep, err);
          flipped += (phi < 0) != (sh.poly(x[0], x[1], x[2]) < 0);
        }
    std::printf("%s given as a polynomial, redistanced: max error %.3f voxel within 2 voxels of the surface, "
                "%.3f deeper inside\n", sh.name, near / h, deep / h);
    EXPECT_EQ(flipped, 0u) << sh.name;
    EXPECT_LE(near, 0.5 * h) << sh.name;
    EXPECT_LE(deep, 1.0 * h) << sh.name;
  }
}
