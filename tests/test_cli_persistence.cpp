// `chokeloops persistence`: CSV rows equal the library's diagram; bad inputs give exit code 2 and a
// one-line error.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <tuple>

#include <openvdb/openvdb.h>

#include "analytic_fields.h"
#include "chokeloops/topology/persistence.h"
#include "chokeloops/io/vdb_io.h"

using namespace chokeloops;
namespace fs = std::filesystem;

namespace {

struct CliResult {
  int code = -1;
  std::string err;
};

class CliPersistence : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("chokeloops_cli_persistence_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  CliResult run(const std::string& args) const {
    std::string err = path("stderr.txt");
    std::string cmd = std::string("'") + CHOKELOOPS_CLI + "' persistence " + args + " >/dev/null 2>'" + err + "'";
    int status = std::system(cmd.c_str());
    CliResult r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    std::ifstream in(err);
    std::stringstream s;
    s << in.rdbuf();
    r.err = s.str();
    return r;
  }

  fs::path dir_;
};

using Row = std::tuple<int, float, float>;

std::vector<Row> read_csv(const std::string& file, std::string* header) {
  std::ifstream in(file);
  std::string line;
  std::getline(in, line);
  if (header) *header = line;
  std::vector<Row> rows;
  while (std::getline(in, line)) {
    std::stringstream s(line);
    std::string a, b, c;
    std::getline(s, a, ',');
    std::getline(s, b, ',');
    std::getline(s, c, ',');
    float death = c == "inf" ? std::numeric_limits<float>::infinity() : std::stof(c);
    rows.emplace_back(std::stoi(a), std::stof(b), death);
  }
  std::sort(rows.begin(), rows.end());
  return rows;
}

int count_lines(const std::string& s) { return int(std::count(s.begin(), s.end(), '\n')); }

TEST_F(CliPersistence, WritesTheDiagramAsCsv) {
  ScalarGrid g = sample_field({20, 20, 20}, analytic::torus(0.3, 0.12));
  add_uniform_noise(g, 0.01, 3);
  write_vdb(g, path("torus.vdb"), "sdf");
  auto r = run("'" + path("torus.vdb") + "' -o '" + path("pairs.csv") + "' --threads 1");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("dim1"), std::string::npos) << r.err;

  std::string header;
  auto rows = read_csv(path("pairs.csv"), &header);
  EXPECT_EQ(header, "dim,birth,death");
  auto d = lower_star_persistence(read_vdb_dense(path("torus.vdb")));
  std::vector<Row> expected;
  for (auto& p : d.pairs) expected.emplace_back(p.dim, p.birth, p.death);
  for (auto& p : d.essential) expected.emplace_back(p.dim, p.birth, std::numeric_limits<float>::infinity());
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(rows, expected);
  // The torus: one dim-1 pair straddling zero, one essential class.
  int genus = 0, essential = 0;
  for (auto& [dim, b, dth] : rows) {
    genus += dim == 1 && b < 0 && dth > 0;
    essential += std::isinf(dth);
  }
  EXPECT_EQ(genus, 1);
  EXPECT_EQ(essential, 1);
  // Same rows with 2 threads and with --grid naming the grid.
  r = run("'" + path("torus.vdb") + "' --grid sdf --threads 2 -o '" + path("pairs2.csv") + "'");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(read_csv(path("pairs2.csv"), nullptr), rows);
}

TEST_F(CliPersistence, BadInputsExitWithCode2AndOneLine) {
  openvdb::initialize();
  // A float grid holding a NaN (written directly: write_vdb refuses non-finite grids).
  {
    auto grid = openvdb::FloatGrid::create(1.f);
    grid->setName("nan");
    auto acc = grid->getAccessor();
    for (int k = 0; k < 3; ++k)
      for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 3; ++i) acc.setValue(openvdb::Coord(i, j, k), float(i + j + k));
    acc.setValue(openvdb::Coord(1, 1, 1), std::nanf(""));
    openvdb::io::File(path("nan.vdb")).write({grid});
  }
  // An empty float grid, and a file with only a non-float grid.
  {
    auto grid = openvdb::FloatGrid::create(1.f);
    grid->setName("empty");
    openvdb::io::File(path("empty.vdb")).write({grid});
    auto ints = openvdb::Int32Grid::create(0);
    ints->setName("ints");
    ints->getAccessor().setValue(openvdb::Coord(0, 0, 0), 5);
    ints->getAccessor().setValue(openvdb::Coord(1, 1, 1), 5);
    openvdb::io::File(path("ints.vdb")).write({ints});
  }
  std::ofstream(path("garbage.vdb")) << "not a vdb file\n";
  ScalarGrid ok = sample_field({4, 4, 4}, analytic::ball(0.3));
  write_vdb(ok, path("ok.vdb"), "sdf");

  for (std::string args : {"'" + path("nan.vdb") + "' -o '" + path("a.csv") + "'",
                           "'" + path("empty.vdb") + "' -o '" + path("a.csv") + "'",
                           "'" + path("ints.vdb") + "' -o '" + path("a.csv") + "'",
                           "'" + path("garbage.vdb") + "' -o '" + path("a.csv") + "'",
                           "'" + path("missing.vdb") + "' -o '" + path("a.csv") + "'",
                           "'" + path("ok.vdb") + "' --grid nosuchgrid -o '" + path("a.csv") + "'",
                           "'" + path("ok.vdb") + "'",  // no -o
                           "'" + path("ok.vdb") + "' -o '" + path("a.csv") + "' --threads 0",
                           "'" + path("ok.vdb") + "' -o '" + path("a.csv") + "' --bogus",
                           "'" + path("ok.vdb") + "' -o '" + path("no/such/dir/a.csv") + "'"}) {
    auto r = run(args);
    EXPECT_EQ(r.code, 2) << args << "\n" << r.err;
    EXPECT_EQ(count_lines(r.err), 1) << args << "\n" << r.err;
    EXPECT_NE(r.err.find("error"), std::string::npos) << r.err;
  }
  EXPECT_FALSE(fs::exists(path("a.csv")));
  auto help = run("--help");
  EXPECT_EQ(help.code, 0);
}

}  // namespace

// A rough field whose pairs need more than --max-memory: exit code 3 and one line saying what to do, where the
// same budget takes the smooth field.
TEST_F(CliPersistence, ARoughFieldOverMaxMemoryExitsWithCode3) {
  ScalarGrid smooth = sample_field({64, 64, 64}, analytic::torus(0.3, 0.12));
  ScalarGrid rough = smooth;
  add_uniform_noise(rough, 0.1, 11);
  const std::size_t es = lower_star_persistence(smooth).stats.estimated_bytes;
  const std::size_t er = lower_star_persistence(rough).stats.estimated_bytes;
  ASSERT_LT(es, er);
  write_vdb(smooth, path("smooth.vdb"), "sdf");
  write_vdb(rough, path("rough.vdb"), "sdf");
  const std::string budget = " --max-memory " + std::to_string((es + er) / 2);
  auto r = run("'" + path("smooth.vdb") + "' -o '" + path("s.csv") + "'" + budget);
  EXPECT_EQ(r.code, 0) << r.err;
  r = run("'" + path("rough.vdb") + "' -o '" + path("r.csv") + "'" + budget);
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_EQ(count_lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("--max-memory"), std::string::npos) << r.err;
}
