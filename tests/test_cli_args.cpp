// Every subcommand reads its options through one reader (tools/args.h): a wrong option, a missing or
// malformed value, an out-of-range number or a second positional gives exit code 2 and one line that names
// the option, before any input is read.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

namespace fs = std::filesystem;

namespace {

struct Outcome {
  int code = -1;
  std::string out, err;
};

std::string read_and_remove(const fs::path& file) {
  std::ifstream in(file);
  std::stringstream s;
  s << in.rdbuf();
  in.close();
  fs::remove(file);
  return s.str();
}

Outcome run_cli(const std::string& args, const std::string& environment = "") {
  const std::string stem = "chokeloops_cli_args_" + std::to_string(::getpid());
  fs::path out = fs::temp_directory_path() / (stem + ".out"), err = fs::temp_directory_path() / (stem + ".err");
  std::string cmd = environment + (environment.empty() ? "" : " ") + std::string("'") + CHOKELOOPS_CLI + "' " + args + " >'" + out.string() + "' 2>'" + err.string() + "'";
  int status = std::system(cmd.c_str());
  Outcome o;
  o.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  o.out = read_and_remove(out);
  o.err = read_and_remove(err);
  return o;
}

int lines(const std::string& s) {
  int n = 0;
  for (char c : s) n += c == '\n';
  return n;
}

struct Case {
  const char* args;
  const char* must_say;
};

TEST(CliArgs, MistakesExitWith2AndOneLineNamingTheOption) {
  // The input files need not exist: arguments are checked first.
  const Case cases[] = {
      {"analyze --bogus", "unknown option --bogus"},
      {"analyze in.obj -o out --resolution", "--resolution needs a value"},
      {"analyze in.obj -o out --resolution abc", "--resolution expects an integer in [8, 4096], got 'abc'"},
      {"analyze in.obj -o out --resolution 4", "--resolution expects an integer in [8, 4096], got '4'"},
      {"analyze in.obj -o out --resolution 100.5", "got '100.5'"},
      {"analyze in.obj -o out --threads 0", "--threads expects an integer in [1, 4096], got '0'"},
      {"analyze in.obj -o out --voxel-size 1e999", "--voxel-size expects a number"},
      {"analyze in.obj -o out --margin nan", "--margin expects a number, got 'nan'"},
      {"analyze a.obj b.obj -o out", "more than one input given ('a.obj' and 'b.obj')"},
      {"levelset in.obj -o out.vdb --iso x", "--iso expects a number, got 'x'"},
      {"levelset in.obj -o out.vdb --resolution 1", "--resolution expects an integer in [2, 100000]"},
      {"persistence f.vdb -o p.csv --threads two", "--threads expects an integer in [1, 4096], got 'two'"},
      {"persistence f.vdb g.vdb -o p.csv", "more than one input file given"},
      {"render out --width 3", "--width expects an integer in [16, 16384], got '3'"},
      {"view out --face-budget", "--face-budget needs a value"},
      {"cut in.off", "usage: chokeloops cut INPUT OUTDIR -o OUTPUT"},
      {"cut in.off out", "no output given (-o OUTPUT)"},
      {"cut in.off out -o cut.off --ids 1,x", "--ids: 'x' is not a loop id"},
      {"cut in.off out -o cut.off --side both", "--side must be handle or tunnel"},
      {"cut in.off out -o cut.txt", "must end in .off, .ply, .obj or .stl"},
      {"cut /nonexistent/in.off /nonexistent/out -o cut.off", "run chokeloops analyze"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.args);
    Outcome o = run_cli(c.args);
    EXPECT_EQ(o.code, 2);
    EXPECT_EQ(lines(o.err), 1) << o.err;
    EXPECT_NE(o.err.find(c.must_say), std::string::npos) << o.err;
  }
}

TEST(CliArgs, ResolutionAcceptsAutoAndIntegers) {
  // Reaches the input stage (and fails there on the missing file), so the options themselves were accepted.
  for (const char* r : {"auto", "64", "4096"}) {
    SCOPED_TRACE(r);
    Outcome o = run_cli(std::string("analyze /nonexistent/in.obj -o /nonexistent/out --resolution ") + r);
    EXPECT_EQ(o.code, 2);
    EXPECT_NE(o.err.find("/nonexistent/in.obj"), std::string::npos) << o.err;
    EXPECT_EQ(o.err.find("--resolution"), std::string::npos) << o.err;
  }
}

TEST(CliAnalyze, SummaryNamesTheStrongestFilteredCandidate) {
  // The bunny's neck lives 3.15% of R_in at 128: filtered at 4%, the summary and loops.json name it.
  const std::string model = std::string(CHOKELOOPS_DATA) + "/meshes/bunny_libigl.off";
  if (!fs::exists(model)) GTEST_SKIP() << model << " not found";
  fs::path dir = fs::temp_directory_path() / ("chokeloops_cli_filtered_" + std::to_string(::getpid()));
  Outcome o = run_cli("analyze '" + model + "' -o '" + dir.string() +
                      "' --resolution 128 --dmax 75% --min-persistence 4% --side handle --quiet --no-view");
  ASSERT_EQ(o.code, 0) << o.err;
  EXPECT_NE(o.out.find("handle loops: 0 generator(s), 0 choke(s)"), std::string::npos) << o.out;
  const auto at = o.out.find("strongest below min persistence: handle ");
  ASSERT_NE(at, std::string::npos) << o.out;
  const std::string line = o.out.substr(at, o.out.find('\n', at) - at);
  EXPECT_EQ(line.find("tunnel"), std::string::npos) << line;  // --side handle
  std::ifstream js(dir / "loops.json");
  nlohmann::json j = nlohmann::json::parse(js);
  const double percent = j["strongest_filtered"]["handle"]["persistence_percent"].get<double>();
  EXPECT_GT(percent, 2.5);
  EXPECT_LT(percent, 4.0);
  EXPECT_TRUE(j["strongest_filtered"]["tunnel"].is_null());
  EXPECT_NEAR(j["strongest_filtered"]["handle"]["depth"].get<double>() / j["scales"]["R_in"].get<double>(), 0.55, 0.03);
  char printed[32];
  std::snprintf(printed, sizeof printed, "(%.3g%% of R_in)", percent);
  EXPECT_NE(line.find(printed), std::string::npos) << line;
  fs::remove_all(dir);
}

}  // namespace

TEST(CliAnalyze, AFailedSelfCheckIsReportedAsABugWithItsOwnExitCode) {
  // A failed internal check is not bad input: exit 4, one line that says it is a bug and names the input.
  const std::string model = std::string(CHOKELOOPS_DATA) + "/meshes/kitten_euclid.off";
  const fs::path dir = fs::temp_directory_path() / ("chokeloops_fault_" + std::to_string(::getpid()));
  Outcome o = run_cli("analyze '" + model + "' -o '" + dir.string() + "' --resolution 48 --quiet");
  ASSERT_EQ(o.code, 0) << o.err;
  o = run_cli("analyze '" + model + "' -o '" + dir.string() + "' --resolution 48 --quiet", "CHOKELOOPS_TEST_FAULT=self-check");
  EXPECT_EQ(o.code, 4);
  EXPECT_EQ(lines(o.err), 1) << o.err;
  EXPECT_NE(o.err.find("internal error (a bug"), std::string::npos) << o.err;
  EXPECT_NE(o.err.find("kitten_euclid.off"), std::string::npos) << o.err;
  EXPECT_NE(o.err.find("please report it"), std::string::npos) << o.err;
  fs::remove_all(dir);
}

#ifdef CHOKELOOPS_HAS_TETGEN
TEST(CliAnalyze, TetgenComplexWritesTheChokesAndLoopsOfAClosedMeshAndRefusesOthers) {
  const std::string data = std::string(CHOKELOOPS_DATA);
  const fs::path dir = fs::temp_directory_path() / ("chokeloops_tetgen_" + std::to_string(::getpid()));
  Outcome o = run_cli("analyze '" + data + "/meshes/kitten_euclid.off' -o '" + dir.string() + "' --complex tetgen --tet-spacing 4");
  ASSERT_EQ(o.code, 0) << o.err;
  EXPECT_NE(o.out.find("complex tetgen"), std::string::npos) << o.out;
  std::ifstream csv(dir / "chokes.csv");
  std::string line;
  int handle_generators = 0, tunnel_generators = 0;
  while (std::getline(csv, line)) handle_generators += line.rfind("handle,generator,", 0) == 0, tunnel_generators += line.rfind("tunnel,generator,", 0) == 0;
  EXPECT_EQ(handle_generators, 1);
  EXPECT_EQ(tunnel_generators, 1);
  // loops.json names the complex and gives each loop on the input's edges, checked there.
  std::ifstream json_file(dir / "loops.json");
  const nlohmann::json j = nlohmann::json::parse(json_file);
  EXPECT_EQ(j.at("complex"), "tetgen");
  int verified_generators = 0;
  for (const auto& l : j.at("loops")) {
    // The choke simplex by its vertices: a handle's edge, a tunnel's triangle.
    EXPECT_EQ(l.at("choke_simplex").at("vertices").size(), l.at("side") == "handle" ? 2u : 3u) << l.at("choke_simplex");
    if (l.at("kind") == "generator" && l.at("found") && l.at("verified") && l.at("check") == "non-contractible" &&
        l.at("edge_path").size() >= 3 && l.at("input_points").size() == l.at("points").size())
      ++verified_generators;
  }
  EXPECT_EQ(verified_generators, 2);
  EXPECT_TRUE(fs::exists(dir / "surface.ply") && fs::exists(dir / "loops.ply") && fs::exists(dir / "loops.obj"));
  for (const std::string& bad : {"/meshes/fertility_vmas.off' --complex tetgen", "/molecules/2kix.pdb' --complex tetgen",
                                 "/meshes/kitten_euclid.off' --complex tetgen --resolution 64",
                                 "/meshes/kitten_euclid.off' --tet-spacing 4", "/meshes/kitten_euclid.off' --complex tets",
                                 "/meshes/kitten_euclid.off' --complex tetgen --tet-quality 1",
                                 "/meshes/kitten_euclid.off' --complex tetgen --tet-grading -1",
                                 "/meshes/kitten_euclid.off' --tet-grading 1"}) {
    o = run_cli("analyze '" + data + bad + " -o '" + dir.string() + "'");
    EXPECT_EQ(o.code, 2) << bad;
    EXPECT_EQ(lines(o.err), 1) << bad << ": " << o.err;
  }
  o = run_cli("analyze '" + data + "/meshes/kitten_euclid.off' -o '" + dir.string() + "' --complex tetgen --max-memory 20M");
  EXPECT_EQ(o.code, 3) << o.err;
  EXPECT_EQ(lines(o.err), 1) << o.err;
  fs::remove_all(dir);
}
#endif
