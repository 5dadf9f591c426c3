// Round trips and error messages of the .vdb IO (stage levelset).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include <openvdb/io/File.h>
#include <openvdb/tools/LevelSetSphere.h>

#include "chokeloops/vdb_io.h"

using namespace chokeloops;
namespace fs = std::filesystem;

namespace {
fs::path temp_dir(const std::string& name) {
  fs::path d = fs::temp_directory_path() / ("chokeloops_vdbio_" + name + "_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

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
