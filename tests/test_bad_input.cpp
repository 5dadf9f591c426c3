// Bad input suite for `chokeloops levelset`: every case exits with code 2 and a one-line
// message naming the file and the problem, never a crash. Fixtures are generated at run time.
// CliRun under ASan/UBSan with scripts/test-sanitize.sh.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>

#include <openvdb/io/Compression.h>
#include <openvdb/io/File.h>

#include "chokeloops/field/levelset.h"
#include "chokeloops/io/mesh_io.h"
#include "chokeloops/io/vdb_io.h"
#include "io/vdb_guard.h"
#include "../fuzz/mesh_levelset_decode.h"
#include "../fuzz/vdb_levelset_decode.h"

namespace fs = std::filesystem;
using namespace chokeloops;

namespace {

struct CliRun {
  int code = -1;
  std::string err;
};

CliRun run_cli(const std::string& args) {
  const std::string cmd = std::string(CHOKELOOPS_CLI) + " levelset " + args + " 2>&1 1>/dev/null";
  CliRun r;
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) return r;
  char buf[4096];
  std::size_t n;
  while ((n = fread(buf, 1, sizeof buf, p)) > 0) r.err.append(buf, n);
  int st = pclose(p);
  r.code = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + (WIFSIGNALED(st) ? WTERMSIG(st) : 0);
  return r;
}

// The bytes of an input kept in fuzz/corpus (e.g. "off/regression-510dc4a98ed0"); empty if it is missing.
std::string fuzz_input(const std::string& name) {
  std::ifstream in(std::string(CHOKELOOPS_SOURCE_DIR) + "/fuzz/corpus/" + name, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

class BadInput : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = fs::temp_directory_path() / ("chokeloops_bad_input_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    out = (dir / "out.vdb").string();
  }
  void TearDown() override { fs::remove_all(dir); }
  std::string write(const std::string& name, const std::string& content) {
    auto p = dir / name;
    std::ofstream(p, std::ios::binary) << content;
    return p.string();
  }
  // Checks exit code 2, one line, names the file (by its file name) and contains `what`.
  void expect_bad(const std::string& path, const std::string& what, const std::string& extra = "") {
    CliRun r = run_cli("'" + path + "' -o '" + out + "' --resolution 16" + extra);
    EXPECT_EQ(r.code, 2) << path << ": " << r.err;
    ASSERT_FALSE(r.err.empty()) << path;
    EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << "not one line: " << r.err;
    EXPECT_NE(r.err.find(fs::path(path).filename().string()), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(what), std::string::npos) << "expected '" << what << "' in: " << r.err;
    EXPECT_EQ(r.err.rfind("chokeloops levelset: error: ", 0), 0u) << r.err;
  }
  // An input kept in fuzz/corpus (e.g. "off/regression-510dc4a98ed0"), written as `file` and refused with `what`.
  void expect_kept_input_refused(const std::string& name, const std::string& file, const std::string& what) {
    const std::string bytes = fuzz_input(name);
    ASSERT_FALSE(bytes.empty()) << "missing kept fuzz input " << name;
    expect_bad(write(file, bytes), what);
  }
  fs::path dir;
  std::string out;
};

const char* kTetOff = "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";

std::string binary_ply_tet() {
  std::string s =
      "ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
      "property float z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n";
  const float v[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  s.append(reinterpret_cast<const char*>(v), sizeof v);
  const int f[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  for (auto& t : f) {
    s.push_back(char(3));
    s.append(reinterpret_cast<const char*>(t), sizeof t);
  }
  return s;
}

std::string binary_stl_tet() {
  std::string s(80, ' ');
  std::uint32_t n = 4;
  s.append(reinterpret_cast<const char*>(&n), 4);
  const float v[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const int f[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  for (auto& t : f) {
    float rec[12] = {0};
    for (int k = 0; k < 3; ++k)
      for (int a = 0; a < 3; ++a) rec[3 + 3 * k + a] = v[t[k]][a];
    s.append(reinterpret_cast<const char*>(rec), sizeof rec);
    s.append(2, '\0');
  }
  return s;
}

}  // namespace

TEST_F(BadInput, GoodFixturesConvert) {
  // the fixtures below are broken versions of these, which do convert
  for (auto [name, content] : {std::pair<std::string, std::string>{"tet.off", kTetOff},
                               {"tet.ply", binary_ply_tet()},
                               {"tet.stl", binary_stl_tet()}}) {
    std::string p = write(name, content);
    CliRun r = run_cli("'" + p + "' -o '" + out + "' --resolution 16 -q");
    EXPECT_EQ(r.code, 0) << name << ": " << r.err;
    TriangleMesh m = read_mesh(p);
    EXPECT_EQ(m.faces.size(), 4u) << name;
  }
}

TEST_F(BadInput, MissingFile) { expect_bad((dir / "nope.obj").string(), "no such file"); }

TEST_F(BadInput, Directory) {
  fs::create_directories(dir / "adir.off");
  expect_bad((dir / "adir.off").string(), "is a directory");
}

TEST_F(BadInput, EmptyFile) {
  expect_bad(write("empty.obj", ""), "empty file");
  expect_bad(write("empty.ply", ""), "empty file");
  expect_bad(write("empty.vdb", ""), "empty file");
}

TEST_F(BadInput, TruncatedBinaryPly) {
  std::string full = binary_ply_tet();
  expect_bad(write("trunc.ply", full.substr(0, full.size() - 20)), "truncated binary PLY");
  expect_bad(write("trunc2.ply", full.substr(0, full.size() - 60)), "truncated binary PLY");
}

TEST_F(BadInput, TruncatedBinaryStl) {
  std::string full = binary_stl_tet();
  expect_bad(write("trunc.stl", full.substr(0, full.size() - 30)), "truncated binary STL");
  expect_bad(write("short.stl", full.substr(0, 50)), "truncated binary STL");
}

TEST_F(BadInput, NanVertex) {
  expect_bad(write("nan.off", "OFF\n4 4 0\n0 0 0\n1 0 nan\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n"),
             "non-finite");
  expect_bad(write("nan.obj", "v 0 0 0\nv 1 0 NaN\nv 0 1 0\nf 1 2 3\n"), "non-finite");
}

TEST_F(BadInput, HugeVertex) {
  expect_bad(write("huge.off", "OFF\n4 4 0\n0 0 0\n1e300 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n"),
             "huge coordinate");
  expect_bad(write("huge.obj", "v 0 0 0\nv 1 0 0\nv 0 1 -1e300\nf 1 2 3\n"), "huge coordinate");
}

TEST_F(BadInput, FaceReferencesMissingVertex) {
  expect_bad(write("badidx.off", "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 9\n3 1 2 3\n"),
             "vertex");
  expect_bad(write("badidx.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n"), "vertex");
}

TEST_F(BadInput, ZeroFaces) {
  expect_bad(write("nofaces.off", "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n"), "no faces");
  expect_bad(write("nofaces.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n"), "no faces");
}

TEST_F(BadInput, UnknownExtension) {
  expect_bad(write("mesh.xyz", kTetOff), "unknown mesh extension");
  expect_bad(write("noext", kTetOff), "unknown mesh extension");
}

TEST_F(BadInput, VdbWithoutFloatGrid) {
  ensure_openvdb_initialized();
  auto g = openvdb::Vec3SGrid::create();
  g->setName("vel");
  g->tree().setValue(openvdb::Coord(0, 0, 0), openvdb::Vec3s(1, 2, 3));
  auto p = (dir / "vectors.vdb").string();
  openvdb::io::File(p).write({g});
  expect_bad(p, "no float grid");
  expect_bad(write("text.vdb", "this is not a vdb file at all\n"), "not a readable VDB");
}

TEST_F(BadInput, GarbageMesh) {
  expect_bad(write("garbage.off", "OFF\nthis is not a mesh\n"), "malformed OFF header");
  expect_bad(write("garbage.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\n1\n"),
             "face element");
}

TEST_F(BadInput, BadArguments) {
  std::string p = write("tet.off", kTetOff);
  CliRun r = run_cli("'" + p + "'");  // no -o
  EXPECT_EQ(r.code, 2);
  r = run_cli("'" + p + "' -o '" + out + "' --resolution abc");
  EXPECT_EQ(r.code, 2);
  r = run_cli("'" + p + "' -o '" + out + "' --bogus");
  EXPECT_EQ(r.code, 2);
  r = run_cli("--help");
  EXPECT_EQ(r.code, 0);
}

TEST_F(BadInput, MemoryGuardNamesResolution) {
  std::string p = write("tet.off", kTetOff);
  CliRun r = run_cli("'" + p + "' -o '" + out + "' --resolution 2000 --max-memory 1G");
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_NE(r.err.find("--resolution "), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << r.err;
  // the suggested resolution fits
  auto pos = r.err.find("--resolution ");
  int fit = std::atoi(r.err.c_str() + pos + 13);
  EXPECT_GT(fit, 100);
  CliRun ok = run_cli("'" + p + "' -o '" + out + "' -q --resolution " + std::to_string(fit) + " --max-memory 1G");
  EXPECT_EQ(ok.code, 0) << ok.err;
}

// Regressions found by fuzzing (scripts/fuzz.sh): each of these crashed or hit undefined behaviour inside
// CGAL's readers or orientation before the input stage checked it.
TEST_F(BadInput, FuzzPlyPropertyBeforeAnyElement) {
  expect_bad(write("prop.ply", "ply\nformat ascii 1.0\nproperty float x\nelement vertex 1\nproperty float y\n"
                               "end_header\n0 0\n"),
             "property before any element");
  expect_bad(write("kw.ply", "ply\nformat ascii 1.0\neleme\x9b\x8b rtex 8\nend_header\n"), "malformed PLY header line");
  expect_bad(write("type.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty fl3oat x\nend_header\n0\n"),
             "unknown type");
  // Found next (a timeout): a vertex element whose properties are all on its own line, so it declares none, and
  // 1777777777 items: each reads nothing, and CGAL made a point for each (regression-06085fdc3510).
  expect_kept_input_refused("ply/regression-06085fdc3510", "none.ply",
                            "PLY element 'vle_?ttle_endian' announces 1 items but declares no property");
  expect_bad(write("none2.ply", "ply\nformat ascii 1.0\nelement vertex 1777777777 property float x\n"
                                "element face 0\nproperty list uchar int vertex_indices\nend_header\n"),
             "PLY element 'vertex' announces 1777777777 items but declares no property");
}

TEST_F(BadInput, FuzzOffCountsBeyondInt) {
  expect_bad(write("float.off", "OFF\n3.38812e+09 1 0\n0 0 0\n"), "is not a non-negative integer");
  expect_bad(write("big.off", "OFF\n3388120000 1 0\n0 0 0\n"), "more than a file of");
  expect_bad(write("neg.off", "OFF\n-4 1 0\n0 0 0\n"), "is not a non-negative integer");
  // binary OFF: big-endian counts after the keyword line (CGAL converted their halfedge estimate to int)
  expect_bad(write("bin.off", std::string("OFF BINARY\n\x30\x20\x30\x20\x30\x0a\x31\x20\0\0\0\0", 23)),
             "binary OFF header announces");
  expect_bad(write("binshort.off", "OFF BINARY\n\0\0"), "truncated binary OFF header");
}

TEST_F(BadInput, FuzzBinaryOffFaceLongerThanTheFile) {
  // CGAL reads a binary face's vertex count as an int32 into a std::size_t and sizes the face by it before reading
  // its indices: a negative or huge count allocated gigabytes. Each count is checked against the bytes left.
  auto be32 = [](std::uint32_t v) {
    return std::string{char(v >> 24), char(v >> 16), char(v >> 8), char(v)};
  };
  auto tet = [&](std::uint32_t first_count) {
    std::string s = "OFF BINARY\n" + be32(4) + be32(4) + be32(0);
    const float points[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (const auto& p : points)
      for (float x : p) {
        std::uint32_t bits;
        std::memcpy(&bits, &x, 4);
        s += be32(bits);
      }
    const std::uint32_t faces[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
    for (int f = 0; f < 4; ++f) {
      s += be32(f == 0 ? first_count : 3);
      for (std::uint32_t v : faces[f]) s += be32(v);
    }
    return s;
  };
  EXPECT_EQ(run_cli("'" + write("tet.off", tet(3)) + "' -o '" + out + "' --resolution 16").code, 0);
  expect_bad(write("huge.off", tet(0x7fffffffu)), "binary OFF face 0 has 2147483647 vertices");
  expect_bad(write("negative.off", tet(0xfffffff0u)), "binary OFF face 0 has -16 vertices");
  expect_bad(write("long.off", tet(16)), "binary OFF face 0 has 16 vertices, more than the 60 bytes");
  // Found by fuzzing (libFuzzer's malloc limit: 11 GB): at the end of the file CGAL's int32 read leaves the face count
  // uninitialised and goes on with it. A file ending inside its vertices or faces is refused (regression-c47e0258d445:
  // 8 faces announced, one byte left).
  expect_kept_input_refused("off/regression-c47e0258d445", "ends.off",
                            "truncated binary OFF file: it ends inside its faces");
  const std::string whole = tet(3);
  expect_bad(write("cut_faces.off", whole.substr(0, whole.size() - 14)), "it ends inside its faces");
  expect_bad(write("cut_vertices.off", whole.substr(0, 60)), "it ends inside its vertices");
}

TEST_F(BadInput, FuzzCoffLineWithoutColourAfterOnesWithIt) {
  // Found by fuzzing (ASan, heap-buffer-overflow in CGAL's File_scanner_OFF::scan_color): CGAL's "has colours" flag
  // is set by the first vertex (or face) with a colour and never cleared, so a later line without one had its
  // colour read past its numbers. The input: a COFF vertex "0 1 1 1" (a colour index), then "0 1 00)".
  expect_kept_input_refused("off/regression-0e7494690950", "vertex.off",
                            "vertex 1 has no colour after vertices with one");
  // Found next: "0+ 0 0" is one number for CGAL (its iformat is the stream's `>>`, which stops at the '+'), so that
  // vertex's colour count went below zero; the checks read numbers the same way now (regression-3dc6bb5f9de1).
  expect_kept_input_refused("off/regression-3dc6bb5f9de1", "plus.off",
                            "no faces (1 vertices, 0 faces)");  // the diagnosis of the whole file
  expect_bad(write("face.off", "COFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1 255 0 0\n3 0 1 3\n3 0 3 2\n3 1 2 3\n"),
             "face 1 has no colour after faces with one");
  // and a COFF file ending before its vertices or faces: CGAL read the colour of the missing line (UBSan: an offset
  // applied to the null data of its empty vector of numbers; regression-d9172e41b69b, "1 0 0" and nothing after it)
  expect_kept_input_refused("off/regression-d9172e41b69b", "ends.off",
                            "truncated COFF file: it ends before vertex 0 of 1");
  expect_bad(write("ends2.off", "COFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1 5\n3 0 1 3 5\n"),
             "truncated COFF file: it ends before face 2 of 4");
  // and an ST4OFF file: CGAL's scanner reads texture coordinates at an index it sets only for coloured files
  // (UBSan, regression-3573396b1447). Homogeneous files with attributes are refused; other files with normals,
  // colours or texture coordinates reach CGAL as the plain OFF of their coordinates and faces.
  expect_kept_input_refused("off/regression-3573396b1447", "st4.off",
                            "ST4OFF (homogeneous coordinates with normals, colours or texture coordinates)");
  const TriangleMesh plain = read_mesh(write("plain.off", kTetOff));
  for (const char* variant :
       {"STOFF\n4 4 0\n0 0 0 .5 .5\n1 0 0 0 1\n0 1 0 1 0\n0 0 1 1 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n",
        "NOFF\n4 4 0\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n0 0 1 0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n",
        "STCNOFF\n4 4 0\n0 0 0 0 0 1 9 .5 .5\n1 0 0 0 0 1 9 0 1\n0 1 0 0 0 1 9 1 0\n0 0 1 0 0 1 9 1 1\n"
        "3 0 2 1 1 2 3\n3 0 1 3 1 2 3\n3 0 3 2 1 2 3\n3 1 2 3 1 2 3\n",
        "4OFF\n4 4 0\n0 0 0 2\n2 0 0 2\n0 2 0 2\n0 0 2 2\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n"}) {
    const TriangleMesh m = read_mesh(write("variant.off", variant));
    EXPECT_EQ(m.vertices, plain.vertices) << variant;
    EXPECT_EQ(m.faces, plain.faces) << variant;
  }
  expect_bad(write("st_ends.off", "STOFF\n4 4 0\n0 0 0 .5 .5\n1 0 0 0 1\n"),
             "truncated STOFF file: it ends before vertex 2 of 4");
  // and an nOFF file, whose body CGAL reads as an OFF body after the dimension (UBSan: a face of 3.7e20 vertices
  // converted to std::size_t, regression-f64bbfd78589)
  const std::string n_off = fuzz_input("off/regression-f64bbfd78589");
  ASSERT_FALSE(n_off.empty());
  CliRun n_run = run_cli("'" + write("n.off", n_off) + "' -o '" + out + "' --resolution 16");
  EXPECT_EQ(n_run.code, 2) << n_run.err;
  EXPECT_EQ(n_run.err.find('\n'), n_run.err.size() - 1) << n_run.err;
  expect_bad(write("n2.off", "nOFF\n3\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n-3 0 3 2\n3 1 2 3\n"),
             "face 2 has -3 vertices");
  EXPECT_EQ(read_mesh(write("n3.off", "nOFF\n3\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n"))
                .faces.size(), 4u);
  // Colours on every line, or on none, or from some line on, read as before.
  for (const char* ok : {"COFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3 1\n3 0 3 2 2\n3 1 2 3 3\n",
                         "COFF\n4 4 0\n0 0 0 9\n1 0 0 9\n0 1 0 9\n0 0 1 9\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n"})
    EXPECT_EQ(run_cli("'" + write("ok.off", ok) + "' -o '" + out + "' --resolution 16").code, 0) << ok;
}

TEST_F(BadInput, FuzzTinyObjectInLargeUnits) {
  // Found by fuzzing (PLY and STL): an object so small that its voxel size cubed is below OpenVDB's 3e-15 made
  // OpenVDB's transform throw its own exception. Refused with exit code 2 and what to do.
  std::string tiny = "OFF\n4 4 0\n0 0 0\n1e-5 0 0\n0 1e-5 0\n0 0 1e-5\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";
  expect_bad(write("tiny.off", tiny), "smallest OpenVDB");
  for (const char* name : {"ply/regression-b45680d4d87f", "stl/regression-bf93d9d201a6"}) {
    const std::string bytes = fuzz_input(name);
    ASSERT_FALSE(bytes.empty()) << name;
    const std::string ext = std::string(name).substr(0, 3);
    CliRun r = run_cli("'" + write("fuzz." + ext, bytes) + "' -o '" + out + "' --resolution 16");
    EXPECT_EQ(r.code, 2) << name << ": " << r.err;
    EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << r.err;
  }
}

TEST_F(BadInput, FuzzNoFaceLeftAfterRemovingDegenerateOnes) {
  // Found by fuzzing (UBSan, optimised build): faces with distinct indices whose points are collinear are all
  // removed as degenerate; CGAL's outward orientation then read the orientation of a component that does not
  // exist. Refused instead: nothing is left to convert.
  expect_kept_input_refused("obj/regression-478ce6d8f6fa", "degenerate.obj", "every face is degenerate");
  expect_bad(write("collinear.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 3 0 0\nf 1 2 3\nf 2 3 4\nf 1 3 4\n"),
             "every face is degenerate");
}

TEST_F(BadInput, FuzzFlatClosedMeshIsNotOriented) {
  // A closed tetrahedron whose four vertices are coplanar encloses no volume: CGAL's outward orientation is
  // undefined on it. It is read and repaired without orienting; the level set then says what is wrong.
  const std::string flat = write("flat.off", "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n");
  chokeloops::TriangleMesh m = chokeloops::read_mesh(flat);
  chokeloops::RepairedMesh r = chokeloops::repair_mesh(m, "flat");
  EXPECT_EQ(r.mesh.vertices.size(), 4u);
  CliRun run = run_cli("'" + flat + "' -o '" + out + "' --resolution 16");
  EXPECT_TRUE(run.code == 0 || run.code == 2) << run.err;
  EXPECT_LE(std::count(run.err.begin(), run.err.end(), '\n'), 3) << run.err;
}

TEST_F(BadInput, FuzzVdbBlockLongerThanItsBuffer) {
  // Found by fuzzing: one changed byte in the length of a value block of bunny_8.vdb made OpenVDB 10's reader
  // copy more raw bytes than the leaf's buffer holds (a heap overflow inside the library). The guard of
  // src/io/vdb_guard.cpp checks each block before OpenVDB's buffer sees it.
  // regression-7fd0598244cf: bunny_8.vdb with the top byte of its first leaf's block length (1760 bytes of blosc)
  // set to 0xff, which makes it a raw block of 7e16 bytes for a 2048-byte buffer; 0e298147d4e5: the fuzzer's
  // crossover doing the same; 5adf9289733f: a length that made OpenVDB allocate 4 GiB.
  for (const char* name : {"regression-7fd0598244cf", "regression-0e298147d4e5", "regression-5adf9289733f"}) {
    const std::string bytes = fuzz_input(std::string("vdb/") + name);
    ASSERT_FALSE(bytes.empty()) << name;
    expect_bad(write(std::string(name) + ".vdb", bytes), "corrupt value block");
  }

  // The same for each way a block's length or blosc header can lie, in a level set written here with blosc.
  ensure_openvdb_initialized();
  auto g = openvdb::FloatGrid::create(3.f);
  g->setName("sdf");
  for (int i = 0; i < 64; ++i) g->tree().setValue(openvdb::Coord(i % 8, i / 8, 1), 0.1f * float(i % 7) - 0.3f);
  const std::string good = (dir / "good.vdb").string();
  {
    openvdb::io::File file(good);
    file.setCompression(openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK);
    file.write({g});
  }
  std::ifstream gin(good, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(gin)), std::istreambuf_iterator<char>());
  // A blosc block: its 8-byte length, then blosc's header (format version 2) whose bytes 12-15 repeat the length.
  std::size_t at = std::string::npos;
  for (std::size_t p = 0; p + 24 <= bytes.size() && at == std::string::npos; ++p) {
    std::int64_t length;
    std::uint32_t header_length;
    std::memcpy(&length, bytes.data() + p, 8);
    std::memcpy(&header_length, bytes.data() + p + 20, 4);
    if (length > 16 && length < 1 << 16 && bytes[p + 8] == 2 && header_length == std::uint64_t(length)) at = p;
  }
  ASSERT_NE(at, std::string::npos);
  auto with = [&](std::size_t offset, auto value) {
    std::string b = bytes;
    std::memcpy(&b[at + offset], &value, sizeof value);
    return b;
  };
  EXPECT_NO_THROW(read_vdb_float_grid(good, "sdf"));
  expect_bad(write("raw.vdb", with(0, std::int64_t(-100000))), "claims 100000 raw bytes");
  expect_bad(write("huge.vdb", with(0, std::int64_t(1) << 40)), "compressed bytes");
  expect_bad(write("min.vdb", with(0, std::numeric_limits<std::int64_t>::min())), "corrupt value block");
  expect_bad(write("nbytes.vdb", with(12, std::uint32_t(1) << 20)), "blosc block's header");
  expect_bad(write("cbytes.vdb", with(20, std::uint32_t(1) << 20)), "blosc block's header");
}

TEST_F(BadInput, FuzzVdbMetadataLongerThanTheFile) {
  // Found by fuzzing, once blocks were guarded: a metadata name whose length claims 1.7 GB made OpenVDB 10 allocate
  // it (regression-c9048a042607). Names, values and the delayed-load table are now checked against the file first.
  auto corpus = [](const std::string& name) { return fuzz_input("vdb/" + name); };
  // regression-9059e41ce871: a blosc table length in the delayed-load table of 1.7 GB, allocated by the guard itself
  // before it was checked against the table's own length.
  for (const char* found_name : {"regression-c9048a042607", "regression-9059e41ce871"}) {
    const std::string found = corpus(found_name);
    ASSERT_FALSE(found.empty()) << found_name;
    expect_bad(write(std::string(found_name) + ".vdb", found), "corrupt metadata");
  }

  const std::string bunny = corpus("bunny_8.vdb");
  auto with = [&](std::size_t at, std::uint32_t value) {
    std::string b = bunny;
    std::memcpy(&b[at], &value, sizeof value);
    return b;
  };
  const std::size_t name = bunny.find("class"), table = bunny.find("__delayedload");
  ASSERT_NE(name, std::string::npos);
  ASSERT_NE(table, std::string::npos);
  expect_bad(write("name.vdb", with(name - 4, 0x7ffffff0u)), "more than the file has left");
  expect_bad(write("value.vdb", with(table + 13, 0x7ffffff0u)), "more than the file has left");
  expect_bad(write("leaves.vdb", with(table + 17, 0xfffffff0u)), "leaves, more than the file holds");
  // the names OpenVDB reads with its grid descriptors and transforms
  const std::size_t type = bunny.find("Tree_float_5_4_3"), map = bunny.find("UniformScaleTranslateMap");
  ASSERT_NE(type, std::string::npos);
  ASSERT_NE(map, std::string::npos);
  expect_bad(write("type.vdb", with(type - 4, 0x7ffffff0u)), "more than the file has left");
  expect_bad(write("map.vdb", with(map - 4, 0x7ffffff0u)), "more than the file has left");
}

TEST_F(BadInput, FuzzVdbChildCountBeyondTheFile) {
  // Found by fuzzing, once metadata was guarded: OpenVDB 10 reads a tree's topology without looking at the stream,
  // so a count of 2^32 children went on allocating nodes past the end of a 33 KB file (1.4 GB). The guard makes the
  // stream throw at its end; this input is now refused before that, by the root check (its buffer count is not 1).
  const std::string bytes = fuzz_input("vdb/regression-f797ba18d54e");
  ASSERT_FALSE(bytes.empty());
  const std::string path = write("children.vdb", bytes);
  try {
    read_vdb_float_grid(path, "");
    ADD_FAILURE() << "accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.exit_code, 2);
    EXPECT_NE(std::string(e.what()).find("children.vdb"), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("corrupt"), std::string::npos) << e.what();
  }
  EXPECT_EQ(run_cli("'" + path + "' -o '" + out + "' --resolution 16").code, 2);
}

TEST_F(BadInput, FuzzVdbRootTileFlagNeitherZeroNorOne) {
  // Found by fuzzing (UBSan): OpenVDB's header code reads a root tile's active flag straight into a bool, and a
  // byte other than 0 or 1 there is undefined behaviour. The guard checks the float grid's root tiles first.
  expect_kept_input_refused("vdb/regression-f1b5600801d0", "tile.vdb",
                            "corrupt metadata");  // its buffer count, checked before the tiles
  // Found next: a grid whose block position lies before its own transform; the guard took the grid being read to be
  // one whose blocks start after the transform, found none and left the tiles unchecked (a flag of 40).
  expect_kept_input_refused("vdb/regression-92cd005d697d", "block.vdb", "a root tile's active flag is 40");
  // and then one whose grid position is past the file: no grid started before the transform, so nothing was checked
  // (UBSan: a flag of 135); now its tree is, and its buffer count is refused first
  expect_kept_input_refused("vdb/regression-007860a7c575", "grid.vdb", "the tree claims 319 buffers, not 1");
}

TEST_F(BadInput, FuzzVdbReadStoppingInsideARootChildFreesIt) {
  // Found by fuzzing: the .vdb harness reached libFuzzer's 2 GB RSS limit after about 6,400 refused files. OpenVDB 10's
  // RootNode::readTopology makes each child of the root (270 KB) before reading it and keeps it only once its read
  // returns, so a file ending inside a child lost the child and everything made under it (ASan's leak check: 305 KB
  // for regression-97adff69922f, bunny_8.vdb cut at 11000 bytes, inside the leaves of the root's child; 270 KB for
  // regression-ec5896e9dbe9, cut at 4000, inside that child's values). The guard's topology reader frees it.
  auto corpus = [](const std::string& name) { return fuzz_input("vdb/" + name); };
  auto refused = [&](const std::string& path) {
    try {
      read_vdb_float_grid(path, "");
      ADD_FAILURE() << path << ": accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.exit_code, 2) << e.what();
      EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(fs::path(path).filename().string()), std::string::npos) << e.what();
    }
  };
  for (const char* name : {"regression-97adff69922f", "regression-ec5896e9dbe9"}) {
    const std::string bytes = corpus(name);
    ASSERT_FALSE(bytes.empty()) << name;
    const unsigned long before = vdb_guard_nodes_freed();
    refused(write(std::string(name) + ".vdb", bytes));
    EXPECT_EQ(vdb_guard_nodes_freed(), before + 1) << name;
    EXPECT_EQ(run_cli("'" + (dir / (std::string(name) + ".vdb")).string() + "' -o '" + out + "' --resolution 16").code, 2);
  }
  // Every cut of the file is refused with one line, and the cuts inside the root's child free it.
  const std::string bunny = corpus("bunny_8.vdb");
  ASSERT_FALSE(bunny.empty());
  const unsigned long before = vdb_guard_nodes_freed();
  int cuts = 0;
  for (std::size_t cut = 101; cut < bunny.size(); cut += 499, ++cuts) refused(write("cut.vdb", bunny.substr(0, cut)));
  EXPECT_GE(vdb_guard_nodes_freed() - before, 10u) << "of " << cuts << " cuts";
  // and the whole file still reads
  EXPECT_GT(read_vdb_float_grid(write("whole.vdb", bunny), "")->activeVoxelCount(), 0u);
}

TEST_F(BadInput, FuzzTouchingComponentsDoNotHangTheOrientation) {
  // Found by fuzzing (fuzz_mesh_levelset, a hang): CGAL's orient_to_bound_a_volume decides the nesting of several
  // components by casting rays from a point of each through the others, and retries random rays for as long as
  // every ray is indeterminate, for ever when that point lies on another component. Components that touch or cross
  // keep their orientation; the conversion then finishes (regression-c5929ddc1ef0: 8 vertices at 2^80, 48 faces).
  const std::string bytes = fuzz_input("mesh_levelset/regression-c5929ddc1ef0");
  ASSERT_FALSE(bytes.empty());
  const TriangleMesh mesh =
      fuzz::decode_mesh_levelset_mesh(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
  ASSERT_EQ(mesh.faces.size(), 48u);
  MeshRepairOptions ro;
  const RepairedMesh repaired = repair_mesh(mesh, "touching", ro);
  EXPECT_TRUE(repaired.report.self_intersecting);
  LevelSetOptions o;
  o.quiet = true;
  o.resolution = fuzz::kMeshLevelsetResolution;
  try {
    const LevelSetResult r = mesh_to_levelset(mesh, o, "touching");
    EXPECT_FALSE(r.grid.values.empty());
  } catch (const Error& e) {
    EXPECT_EQ(e.exit_code, 2) << e.what();
  }
}

TEST_F(BadInput, FuzzFogWhoseBackgroundIsDenserThanTheIsoValueIsRefused) {
  // Found by fuzzing (fuzz_vdb_levelset): a grid of unknown class with only non-negative values is read as a fog
  // volume, and its background, 12, lies above the iso value 0.5: every voxel not stored would be inside, so the
  // inside fills all space. OpenVDB's fogToSdf threw a ValueError from its sweeping ("the inside value must be
  // negative"), which is not an Error: the harness ended in std::terminate.
  const std::string bytes = fuzz_input("vdb_levelset/regression-c9222b5eacc3");
  ASSERT_FALSE(bytes.empty());
  ensure_openvdb_initialized();
  const openvdb::FloatGrid::Ptr grid =
      fuzz::decode_vdb_levelset_grid(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
  ASSERT_TRUE(grid);
  ASSERT_GT(grid->background(), 0.5f);
  LevelSetOptions o;
  o.quiet = true;
  try {
    levelset_from_vdb(grid, o, "fog");
    ADD_FAILURE() << "accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.exit_code, 2);
    EXPECT_NE(std::string(e.what()).find("background value 12"), std::string::npos) << e.what();
  }
  // The same grid in a file, through the CLI: exit code 2 and one line; with an iso value above the background it
  // is a fog volume like any other.
  grid->setGridClass(openvdb::GRID_FOG_VOLUME);
  const std::string path = (dir / "dense_background.vdb").string();
  openvdb::io::File(path).write({grid});
  expect_bad(path, "is not below the iso value 0.5");
  o.iso = 100;
  EXPECT_NO_THROW(levelset_from_vdb(grid, o, "fog"));
}

TEST_F(BadInput, FuzzPlyListLongerThanTheFile) {
  // Found by fuzzing, once the PLY harness parsed without converting: CGAL's PLY reader sizes a list by the count the
  // file gives before reading it, so a face of 2^31 indices in a file of 708 bytes allocated 8 GB
  // (regression-f4ad5f56b297: its second line says binary, which CGAL follows, and a later format line said ascii,
  // which this check followed). The format is taken from the second line only, and the body is walked as CGAL reads
  // it, every list checked against what the file has left.
  expect_kept_input_refused("ply/regression-f4ad5f56b297", "found.ply", "format line other than its second line");

  const std::string head =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n";
  const std::string tri = "0 0 0\n1 0 0\n0 1 0\n";
  expect_bad(write("ascii.ply", head + "element face 1\nproperty list int int vertex_indices\nend_header\n" + tri +
                                    "2000000000 0 1 2\n"),
             "PLY list of 2000000000 items");
  // a count CGAL's `>>` finds inside what looks like one token
  expect_bad(write("hidden.ply", head + "element face 1\nproperty list uchar int a\nproperty list int int b\n"
                                        "end_header\n" + tri + "3 0 1 2+2000000000 0\n"),
             "PLY list of 2000000000 items");
  // binary, both byte orders
  for (const bool big : {false, true}) {
    std::string b = std::string("ply\nformat ") + (big ? "binary_big_endian" : "binary_little_endian") +
                    " 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                    "element face 1\nproperty list int int vertex_indices\nend_header\n";
    b.append(36, '\0');
    b += big ? std::string("\x7f\xff\xff\xff", 4) : std::string("\xff\xff\xff\x7f", 4);
    b.append(12, '\0');
    expect_bad(write(big ? "big.ply" : "little.ply", b), "PLY list of 2147483647 items");
  }
  // the same files with a true count still read
  EXPECT_EQ(read_mesh(write("good.ply", head + "element face 1\nproperty list int int vertex_indices\nend_header\n" +
                                            tri + "3 0 1 2\n")).faces.size(), 1u);
  // Found next (libFuzzer's 2 GB RSS limit): an ASCII list count of 42 digits; the extraction fails but leaves
  // INT_MAX, and CGAL sizes the list by it before it looks at the stream (regression-40444d22dd05).
  expect_kept_input_refused("ply/regression-40444d22dd05", "digits.ply", "PLY list of 2147483647 items in element 0");
  expect_bad(write("digits2.ply", head + "element face 1\nproperty list int int vertex_indices\nend_header\n" + tri +
                                      "99999999999999999999 0 1 2\n"),
             "PLY list of 2147483647 items");
}

TEST_F(BadInput, FuzzPlyBodyFailingBeforeAListIsRefused) {
  // Found by fuzzing, only now and then (libFuzzer's malloc limit: 8 GB): once a read of an ASCII PLY body fails,
  // CGAL reads the rest of the element from the failed stream, which leaves each value as it was, so a list count
  // was whatever its uninitialised variable held (regression-71597e842c05: the file ends inside its vertices, whose
  // element has a list). Where a list is still to come, a body that fails is refused.
  expect_kept_input_refused("ply/regression-71597e842c05", "found.ply",
                            "ASCII PLY body ends or holds something other than a number in element 0, item 6");
  const std::string head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                           "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  expect_bad(write("ends.ply", head + "0 0 0\n1 0 0\n0 1\n"), "in element 0, item 2, before a list's count");
  expect_bad(write("word.ply", head + "0 0 0\n1 x 0\n0 1 0\n3 0 1 2\n"), "in element 0, item 1, before a list's count");
  std::string bin = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                    "property float z\nelement face 2\nproperty list int int vertex_indices\nend_header\n";
  bin.append(36, '\0');
  bin += std::string("\x07\0\0\0", 4);  // a first face of 7 indices: the file is as long as two triangles need,
  bin.append(28, '\0');                   // and ends where the second face's count should be
  expect_bad(write("bin_ends.ply", bin), "binary PLY body ends or holds something other than a number in element 1, item 1");
  // the whole file still reads, and an ASCII file without lists ahead is left to CGAL's own message
  EXPECT_EQ(read_mesh(write("good.ply", head + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")).faces.size(), 1u);
}

TEST_F(BadInput, FuzzOffBinaryKeywordAfterComments) {
  // Found by fuzzing (UBSan in CGAL's OFF header): a keyword ending in a byte that is not a letter, a comment, and
  // BINARY on the next line (regression-510dc4a98ed0). CGAL reads that as a binary header and took text for
  // counts of 3.4e9; the header is now scanned the way CGAL scans it, and the counts checked against the file.
  expect_kept_input_refused("off/regression-510dc4a98ed0", "found.off", "binary OFF header announces");
  expect_bad(write("comment.off", "# a comment\nOFF # another\n# and one more\n3000000000 1 0\n0 0 0\n"),
             "more than a file of");
  EXPECT_EQ(read_mesh(write("good.off", std::string("# c\n") + kTetOff)).faces.size(), 4u);

  // Found next: CGAL reads a face line's numbers as double and converts them to std::size_t (UBSan: a face of -20
  // vertices, regression-c6578a24fa42). Negative, huge or non-finite vertex counts and indices are refused first.
  expect_kept_input_refused("off/regression-c6578a24fa42", "face.off", "face 1 has -20 vertices");
  expect_bad(write("index.off", "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 -3\n3 0 3 2\n3 1 2 3\n"),
             "face 1 references vertex -3");
  expect_bad(write("nan.off", "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1 # c\n# c\n3 0 2 1\n3 0 1 3\n1e30 0 3 2\n3 1 2 3\n"),
             "face 2 has 1e+30 vertices");
  // and a vertex line without its numbers (UBSan in CGAL's texture coordinates: regression-09a7fc5d721a, STOFF)
  expect_kept_input_refused("off/regression-09a7fc5d721a", "stoff.off",
                            "truncated OFF file");  // what the diagnosis of the whole file says
  expect_bad(write("short.off", "OFF\n4 4 0\n0 0 0\n1 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n"),
             "vertex 1 has 2 numbers");
  // and an edge count CGAL doubles into an int (regression-24130c2839b8: nOFF, binary)
  expect_kept_input_refused("off/regression-24130c2839b8", "edges.off", "edges (malformed)");
  expect_bad(write("edges2.off", "OFF\n4 4 2000000000\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n"),
             "OFF header announces 2000000000 edges");
  // and a face whose count CGAL allocates before finding its indices missing (4.4 GB: regression-20686756b7fb)
  expect_kept_input_refused("off/regression-20686756b7fb", "count.off", "indices");
  expect_bad(write("count2.off", "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n555555555 0 1 3\n3 0 3 2\n3 1 2 3\n"),
             "face 1 has 555555555 vertices but its line holds 3 indices");
  // and a COFF vertex "0+ 1 0", one number for CGAL, whose colour CGAL then read past (ASan: regression-53d38fc2d606;
  // first taken for a face line without numbers, fixed by reading numbers as CGAL does:
  // FuzzCoffLineWithoutColourAfterOnesWithIt), and COFF colours of 2 numbers
  expect_kept_input_refused("off/regression-53d38fc2d606", "colour.off",
                            "vertex 0 has 1 numbers, fewer than the 3 a COFF vertex needs");
  expect_bad(write("colour1.off", "COFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\nx y\n"), "face 0 has no numbers");
  expect_bad(write("colour2.off", "COFF\n3 1 0\n0 0 0 1 2\n1 0 0\n0 1 0\n3 0 1 2\n"), "colour numbers");
  EXPECT_EQ(read_mesh(write("coff.off", "COFF\n4 4 0\n0 0 0 255 0 0\n1 0 0 0 255 0\n0 1 0 0 0 255\n0 0 1 9 9 9 1\n"
                                        "3 0 2 1\n3 0 1 3 7\n3 0 3 2 8\n3 1 2 3 9\n")).faces.size(), 4u);
}
