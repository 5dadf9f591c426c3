// Benchmark of medical volumes end to end: read → signed distance on the image lattice →
// persistence → chokes → surface → loops → report + label volumes, per-stage wall times and the peak RSS of
// each case (each case runs in a forked child, whose getrusage maxrss is the case's alone).
// usage: bench_volumes [--max-loops N] [case...]   (loops traced for the N most persistent chokes; default 20)
//        cases: gm (MNI GM map, --iso 128), t1 (MNI T1, --iso 80),
//                                         vessel:N (synthetic vessel tree mask, N^3 voxels; default 512)
// Default: gm t1 vessel:512.
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "chokeloops/huge_pages.h"
#include "chokeloops/analyze_volume.h"

using namespace chokeloops;
using Clock = std::chrono::steady_clock;

namespace {

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// A deterministic branching tree of capsules (radius and length shrink by 0.75 a level) plus a few
// anastomoses between leaves (handles), rasterised into an N^3 uint8 mask at 0.5 mm.
VolumeImage vessel_tree(int n) {
  VolumeImage v;
  v.path = "vessel_tree_" + std::to_string(n);
  v.format = "nifti1";
  v.dims = {n, n, n};
  v.datatype = "uint8";
  v.integer_type = true;
  v.convention = "RAS";
  for (int r = 0; r < 3; ++r) v.affine[r][r] = 0.5, v.spacing[r] = 0.5;
  v.values.assign(std::size_t(n) * n * n, 0.f);
  struct Seg { double a[3], b[3], r; };
  std::vector<Seg> segs;
  unsigned long long state = 12345;
  auto rnd = [&] { state = state * 6364136223846793005ULL + 1442695040888963407ULL; return double(state >> 11) / double(1ULL << 53); };
  struct Node { double p[3], d[3], r, len; int level; };
  std::vector<Node> stack = {{{n / 2.0, n / 2.0, 0.04 * n}, {0, 0, 1}, 0.035 * n, 0.28 * n, 0}};
  std::vector<std::array<double, 3>> leaves;
  while (!stack.empty()) {
    Node nd = stack.back();
    stack.pop_back();
    Seg s;
    for (int c = 0; c < 3; ++c) s.a[c] = nd.p[c], s.b[c] = nd.p[c] + nd.len * nd.d[c];
    s.r = nd.r;
    segs.push_back(s);
    if (nd.level == 6 || nd.r < 1.0) { leaves.push_back({s.b[0], s.b[1], s.b[2]}); continue; }
    for (int child = 0; child < 2; ++child) {
      Node c = nd;
      for (int q = 0; q < 3; ++q) c.p[q] = s.b[q];
      double dir[3];
      for (int q = 0; q < 3; ++q) dir[q] = nd.d[q] + (rnd() - 0.5) * 1.2 + (child ? 0.35 : -0.35) * (q == 0) ;
      double len = std::sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
      for (int q = 0; q < 3; ++q) c.d[q] = dir[q] / len;
      c.r = nd.r * 0.75;
      c.len = nd.len * 0.75;
      c.level = nd.level + 1;
      stack.push_back(c);
    }
  }
  // anastomoses: each leaf to the nearest other leaf not already its sibling
  for (std::size_t i = 0; i + 1 < leaves.size(); i += 7) {
    Seg s;
    for (int c = 0; c < 3; ++c) s.a[c] = leaves[i][c], s.b[c] = leaves[(i + leaves.size() / 2) % leaves.size()][c];
    s.r = 1.2;
    segs.push_back(s);
  }
  for (const Seg& s : segs) {
    int lo[3], hi[3];
    for (int c = 0; c < 3; ++c) {
      lo[c] = std::max(0, int(std::floor(std::min(s.a[c], s.b[c]) - s.r - 1)));
      hi[c] = std::min(n - 1, int(std::ceil(std::max(s.a[c], s.b[c]) + s.r + 1)));
    }
    double ab[3] = {s.b[0] - s.a[0], s.b[1] - s.a[1], s.b[2] - s.a[2]};
    const double ab2 = ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2];
    for (int k = lo[2]; k <= hi[2]; ++k)
      for (int j = lo[1]; j <= hi[1]; ++j)
        for (int i = lo[0]; i <= hi[0]; ++i) {
          double ap[3] = {i - s.a[0], j - s.a[1], k - s.a[2]};
          double t = ab2 > 0 ? (ap[0] * ab[0] + ap[1] * ab[1] + ap[2] * ab[2]) / ab2 : 0;
          t = std::min(1.0, std::max(0.0, t));
          double d2 = 0;
          for (int c = 0; c < 3; ++c) d2 += (ap[c] - t * ab[c]) * (ap[c] - t * ab[c]);
          if (d2 <= s.r * s.r) v.values[std::size_t(i) + std::size_t(n) * (j + std::size_t(n) * k)] = 1.f;
        }
  }
  return v;
}

int g_max_loops = 20;

void run_case(const std::string& name) {
  auto t0 = Clock::now();
  VolumeImage img;
  VolumeFieldOptions f;
  const std::string data = std::string(CHOKELOOPS_SOURCE_DIR) + "/data/volumes/";
  double read_s = 0;
  if (name == "gm" || name == "t1") {
    img = read_volume(data + (name == "gm" ? "mni_icbm152_gm_tal_nlin_sym_09a_converted.nii.gz"
                                           : "mni_icbm152_t1_tal_nlin_sym_09a_converted.nii.gz"));
    f.has_iso = true;
    f.iso = name == "gm" ? 128 : 80;
    read_s = seconds_since(t0);
  } else if (name.rfind("vessel", 0) == 0) {
    const int n = name.size() > 7 ? std::atoi(name.c_str() + 7) : 512;
    img = vessel_tree(n);
    f.has_label = true;
    f.label = 1;
    read_s = seconds_since(t0);  // synthesis, not reading
  } else {
    std::fprintf(stderr, "unknown case %s\n", name.c_str());
    std::exit(2);
  }
  AnalyzeOptions o;
  o.max_loops = g_max_loops;
  VolumeAnalysis a = analyze_volume(img, f, o);
  auto t1 = Clock::now();
  const std::string out = (std::filesystem::temp_directory_path() / ("bench_volumes_" + name)).string();
  write_report(a.result, o, out);
  write_loop_volumes(a, img, out);
  const double report_s = seconds_since(t1);
  const double total = seconds_since(t0);
  struct rusage u;
  getrusage(RUSAGE_SELF, &u);
  const AnalyzeResult& r = a.result;
  auto ms = [&](const char* k) { auto it = r.timings_ms.find(k); return it == r.timings_ms.end() ? 0.0 : it->second / 1000; };
  std::printf("%-12s %4dx%4dx%4d %8zu %6d %6d %6zu | %6.2f %6.2f %6.2f %6.2f %6.2f %6.2f %6.2f %6.2f | %7.2f s %8.0f MB\n",
              name.c_str(), r.grid.dims[0], r.grid.dims[1], r.grid.dims[2], std::size_t(r.surface_stats.vertices),
              r.surface_stats.genus, r.chokes.handle_generators, r.loops.size(), read_s, ms("levelset"),
              ms("persistence"), ms("chokes"), ms("surface"), ms("loops"), ms("check"), report_s, total,
              u.ru_maxrss / 1024.0);
  std::filesystem::remove_all(out);
}

}  // namespace

int main(int argc, char** argv) {
  chokeloops::restart_with_huge_pages(argv);
  std::vector<std::string> cases;
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]) == "--max-loops" && i + 1 < argc) g_max_loops = std::atoi(argv[++i]);
    else cases.push_back(argv[i]);
  }
  if (cases.empty()) cases = {"gm", "t1", "vessel:512"};
  std::printf("%-12s %14s %8s %6s %6s %6s | %6s %6s %6s %6s %6s %6s %6s %6s | %9s %11s\n", "case", "grid", "surf #v",
              "genus", "h-gen", "loops", "read", "field", "pers", "chokes", "surf", "loops", "check", "report",
              "total", "peak RSS");
  std::fflush(stdout);
  for (auto& c : cases) {
    pid_t pid = fork();
    if (pid == 0) {
      try {
        run_case(c);
      } catch (const std::exception& e) {
        std::printf("%-12s error: %s\n", c.c_str(), e.what());
      }
      std::fflush(stdout);
      _exit(0);
    }
    int status = 0;
    waitpid(pid, &status, 0);
    if (WIFSIGNALED(status)) std::printf("%-12s killed by signal %d\n", c.c_str(), WTERMSIG(status));
  }
  std::printf("(seconds; read = image reading / synthesis; field = signed distance on the padded lattice; loops\n"
              " traced for the --max-loops most persistent chokes; peak RSS of the case's own process)\n");
  return 0;
}
