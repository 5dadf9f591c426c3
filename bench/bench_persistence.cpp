// Benchmark of lower-star persistence:
//   torus        signed distance of a torus R = 0.3, r = 0.12 centred in the unit cube, x_i = i/(n-1)
//   torus+noise  the same plus uniform noise in [-0.02, 0.02] (fixed seed)
//   random       a smooth random field: sum of 30 random Gaussian bumps (fixed seed)
// at 128^3 and 256^3 (and 512^3 with --large). Each configuration runs in a fresh child process
// (fork), so the peak RSS printed (getrusage ru_maxrss) is that configuration's: it includes the
// input field (4 bytes per vertex) and the diagram. Times are medians over --runs runs (default 5)
// of each phase (PersistenceDiagram::stats) and of the whole lower_star_persistence call.
// --peer-phat MAX_N also runs the peer on every size up to MAX_N, in the same run on the same field:
// PHAT's twist reduction of the explicit boundary matrix (tests/phat_oracle.h), with its time, peak RSS,
// the ratio to chokeloops' wall time, and a check that both give the same number of pairs.
// --peer-cubicalripser BIN runs CubicalRipser (built from its public sources, bench/README.md) on the same
// field, written as a float64 .npy, in its own process: wall time from exec to exit (reading the .npy
// included, as chokeloops' wall time here excludes making the field), peak RSS by wait4, median of
// min(runs, 3). Its pairs are those of the cubical complex (V-construction), not Freudenthal's, so only the
// times and the memory are compared.
// --peer-ttk BIN runs TTK's DiscreteMorseSandwich (bench/peers/ttk_persistence.cpp, built from TTK's public
// sources, bench/README.md) the same way on the field mirrored along x, where its triangulation is ours; up to
// --peer-ttk-compare MAX_N (default 128) its diagram is also compared with chokeloops', pair for pair.
//
// usage: bench_persistence [--runs R] [--large] [--sizes 128,256] [--fields torus,noise,random]
//                          [--threads N] [--peer-phat MAX_N] [--peer-cubicalripser BIN] [--peer-ttk BIN]
//                          [--peer-ttk-compare MAX_N]
#include <sys/resource.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <tbb/global_control.h>
#include <tbb/info.h>

#include "chokeloops/huge_pages.h"
#include "chokeloops/field/analytic.h"
#include "chokeloops/topology/persistence.h"
#include "../tests/phat_oracle.h"
#include "peer_process.h"

using namespace chokeloops;
using bench::run_peer;
using bench::write_raw_mirrored_x;

namespace {

struct Result {
  int ok = 0;
  double classify = 0, dim0 = 0, dim2 = 0, dim1 = 0, total = 0, wall = 0, make_field = 0;
  long long pairs[3] = {0, 0, 0};
  long long essential = 0, join_saddles = 0, split_saddles = 0, minima = 0, maxima = 0;
  double peak_rss_mb = 0, estimate_mb = 0;
  char error[200] = {0};
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

ScalarGrid make_field(const std::string& name, int n) {
  if (name == "torus" || name == "noise") {
    ScalarGrid g = sample_field({n, n, n}, analytic::torus(0.3, 0.12));
    if (name == "noise") add_uniform_noise(g, 0.02, 2026);
    return g;
  }
  if (name == "random") return sample_field({n, n, n}, analytic::random_gaussians(30, 2026));
  throw std::invalid_argument("unknown field '" + name + "' (torus, noise, random)");
}

const char* field_label(const std::string& name) {
  if (name == "torus") return "torus SDF";
  if (name == "noise") return "torus SDF + noise 0.02";
  if (name == "random") return "smooth random (30 Gaussians)";
  return name.c_str();
}

// The peer: PHAT's twist reduction of the explicit boundary matrix of the same filtered complex (the
// oracle of the tests), timed from the field to the pairs. Single-threaded, as PHAT's twist is.
void measure_phat(const ScalarGrid& g, int runs, Result& r) {
  std::vector<double> wall;
  for (int i = 0; i < runs; ++i) {
    auto s = std::chrono::steady_clock::now();
    oracle::OracleDiagram d = oracle::phat_persistence(g);
    wall.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - s).count());
    for (int k = 0; k < 3; ++k) r.pairs[k] = 0;
    for (auto& p : d.pairs) if (p.dim < 3) ++r.pairs[p.dim];
    r.essential = (long long)d.essential.size();
  }
  r.total = r.wall = median(wall);
}

Result measure(const std::string& field, int n, int runs, bool phat) {
  Result r;
  auto t0 = std::chrono::steady_clock::now();
  ScalarGrid g = make_field(field, n);
  r.make_field = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::vector<double> cl, d0, d2, d1, tot, wall;
  if (phat) {
    measure_phat(g, runs, r);
    runs = 0;
  }
  for (int i = 0; i < runs; ++i) {
    auto s = std::chrono::steady_clock::now();
    PersistenceDiagram d = lower_star_persistence(g);
    wall.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - s).count());
    cl.push_back(d.stats.seconds_classify);
    d0.push_back(d.stats.seconds_dim0);
    d2.push_back(d.stats.seconds_dim2);
    d1.push_back(d.stats.seconds_dim1);
    tot.push_back(d.stats.seconds_total);
    for (int k = 0; k < 3; ++k) r.pairs[k] = (long long)d.count(k);
    r.essential = (long long)d.essential.size();
    r.join_saddles = d.stats.join_saddles;
    r.split_saddles = d.stats.split_saddles;
    r.minima = d.stats.minima;
    r.maxima = d.stats.maxima;
    r.estimate_mb = double(d.stats.estimated_bytes) / double(1 << 20);
  }
  if (!phat) {
    r.classify = median(cl);
    r.dim0 = median(d0);
    r.dim2 = median(d2);
    r.dim1 = median(d1);
    r.total = median(tot);
    r.wall = median(wall);
  }
  struct rusage ru;
  getrusage(RUSAGE_SELF, &ru);
  r.peak_rss_mb = double(ru.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
  r.ok = 1;
  return r;
}

// The field as a C-order float64 .npy (NumPy format 1.0), axis 0 slowest: the layout CubicalRipser reads.
void write_npy(const ScalarGrid& g, const std::string& path) {
  std::ofstream out(path, std::ios::binary);
  std::string header = "{'descr': '<f8', 'fortran_order': False, 'shape': (" + std::to_string(g.dims[2]) + ", " +
                       std::to_string(g.dims[1]) + ", " + std::to_string(g.dims[0]) + "), }";
  header.append(64 - (10 + header.size() + 1) % 64, ' ');
  header += '\n';
  const unsigned short len = (unsigned short)header.size();
  out.write("\x93NUMPY\x01\x00", 8);
  out.write(reinterpret_cast<const char*>(&len), 2);
  out << header;
  std::vector<double> row(g.values.size());
  for (std::size_t i = 0; i < row.size(); ++i) row[i] = g.values[i];  // x fastest: the grid's own order
  out.write(reinterpret_cast<const char*>(row.data()), std::streamsize(row.size() * sizeof(double)));
  if (!out) throw std::runtime_error("cannot write " + path);
}

// Runs a peer's argv `runs` times: r's wall time (median) and peak RSS (largest), r.ok; false with `error`
// set at the first failing run.
bool time_peer(const std::vector<std::string>& argv, int runs, Result& r, std::string& error) {
  std::vector<double> wall;
  for (int i = 0; i < runs; ++i) {
    double sec = 0, mb = 0;
    if (!run_peer(argv, sec, mb, error)) return false;
    wall.push_back(sec);
    r.peak_rss_mb = std::max(r.peak_rss_mb, mb);
  }
  r.total = r.wall = median(wall);
  r.ok = 1;
  return true;
}

// Runs `work` in a forked child and waits for it; true if it exited 0. The peers' input files (and the diagram
// TTK's is compared with) are made there: this process must not start TBB's workers itself, or every later
// child it forks to measure chokeloops inherits a scheduler whose workers did not survive the fork and runs
// on one thread (noisy 256^3 after the 128^3 peers: dim 1 10.8 s where it takes 5.8 s).
template <class Work>
bool in_child(Work&& work) {
  std::fflush(stdout);
  const pid_t pid = fork();
  if (pid < 0) return false;
  if (pid == 0) {
    bool ok = false;
    try {
      ok = work();
    } catch (const std::exception& e) {
      std::fprintf(stderr, "bench_persistence: %s\n", e.what());
    }
    std::fflush(stdout);
    _exit(ok ? 0 : 1);
  }
  int status = 0;
  if (waitpid(pid, &status, 0) != pid) return false;
  return WIFEXITED(status) && WEXITSTATUS(status) == 0;
}

// CubicalRipser on the same field: dims 0-2, no output file, median wall time of `runs`.
Result measure_cubicalripser(const std::string& bin, const std::string& field, int n, int runs) {
  Result r;
  char dir[] = "/tmp/bench_persistence_XXXXXX";
  if (!mkdtemp(dir)) { std::snprintf(r.error, sizeof r.error, "mkdtemp failed"); return r; }
  const std::string npy = std::string(dir) + "/field.npy";
  if (!in_child([&] {
        write_npy(make_field(field, n), npy);
        return true;
      })) {
    std::snprintf(r.error, sizeof r.error, "could not write the peer's field to %s", npy.c_str());
    rmdir(dir);
    return r;
  }
  std::string error;
  if (!time_peer({bin, "--maxdim", "2", "--output", "none", npy}, runs, r, error))
    std::snprintf(r.error, sizeof r.error, "%s", error.c_str());
  std::remove(npy.c_str());
  rmdir(dir);
  return r;
}

struct ValuePair {
  int dim;
  float birth, death;
  bool operator<(const ValuePair& o) const {
    return dim != o.dim ? dim < o.dim : birth != o.birth ? birth < o.birth : death < o.death;
  }
  bool operator==(const ValuePair& o) const { return dim == o.dim && birth == o.birth && death == o.death; }
};

// How many pairs of `a` and `b` (as multisets of (dim, birth, death)) have no match in the other.
std::size_t unmatched_pairs(std::vector<ValuePair> a, std::vector<ValuePair> b) {
  std::sort(a.begin(), a.end());
  std::sort(b.begin(), b.end());
  std::size_t i = 0, j = 0, unmatched = 0;
  while (i < a.size() && j < b.size()) {
    if (a[i] == b[j]) { ++i; ++j; }
    else if (a[i] < b[j]) { ++i; ++unmatched; }
    else { ++j; ++unmatched; }
  }
  return unmatched + (a.size() - i) + (b.size() - j);
}

// TTK's persistence diagram (DiscreteMorseSandwich, bench/peers/ttk_persistence.cpp) on the same field, in its
// own process, as raw float32 mirrored along x: TTK splits each cube of the grid along its (1,0,0)-(0,1,1)
// diagonal and chokeloops along (0,0,0)-(1,1,1), so TTK's triangulation of the mirrored field is chokeloops'
// triangulation of the field, and the two diagrams must be the same pairs. Wall time from exec to exit (reading
// the raw file included), peak RSS by wait4, median of min(runs, 3). With `compare`, one more run (untimed)
// writes TTK's pairs, which are compared with chokeloops' on the unmirrored field; `verdict` says how they agree.
Result measure_ttk(const std::string& bin, const std::string& field, int n, int runs, int threads, bool compare,
                   std::string& verdict) {
  Result r;
  char dir[] = "/tmp/bench_persistence_XXXXXX";
  if (!mkdtemp(dir)) { std::snprintf(r.error, sizeof r.error, "mkdtemp failed"); return r; }
  const std::string raw = std::string(dir) + "/field.raw", csv = std::string(dir) + "/pairs.csv";
  const std::string ours_file = std::string(dir) + "/ours.bin";  // chokeloops' pairs, as ValuePair records
  auto read_pairs = [](const std::string& path) {
    std::vector<ValuePair> pairs;
    std::ifstream in(path);
    ValuePair v{};
    char c1, c2;
    while (in >> v.dim >> c1 >> v.birth >> c2 >> v.death) pairs.push_back(v);
    return pairs;
  };
  if (!in_child([&] {
        ScalarGrid g = make_field(field, n);
        write_raw_mirrored_x(g, raw);
        if (!compare) return true;
        std::vector<ValuePair> pairs;
        for (auto& p : lower_star_persistence(g).pairs) pairs.push_back({p.dim, p.birth, p.death});
        std::ofstream out(ours_file, std::ios::binary);
        out.write(reinterpret_cast<const char*>(pairs.data()), std::streamsize(pairs.size() * sizeof(ValuePair)));
        return bool(out);
      })) {
    std::snprintf(r.error, sizeof r.error, "could not write the peer's field to %s", raw.c_str());
    std::remove(raw.c_str());
    rmdir(dir);
    return r;
  }
  std::vector<ValuePair> ours;
  if (compare) {
    std::ifstream in(ours_file, std::ios::binary);
    ValuePair v{};
    while (in.read(reinterpret_cast<char*>(&v), sizeof v)) ours.push_back(v);
    std::remove(ours_file.c_str());
  }
  const std::string t = std::to_string(threads > 0 ? threads : tbb::info::default_concurrency()), ns = std::to_string(n);
  std::string error;
  if (time_peer({bin, raw, ns, ns, ns, t}, runs, r, error) && compare) {
    double sec = 0, mb = 0;
    if (run_peer({bin, raw, ns, ns, ns, t, csv}, sec, mb, error)) {
      const std::vector<ValuePair> theirs = read_pairs(csv);
      const std::size_t bad = unmatched_pairs(ours, theirs);
      verdict = bad == 0 ? "diagram identical to chokeloops' (" + std::to_string(ours.size()) + " pairs)"
                         : "DIAGRAMS DIFFER: " + std::to_string(bad) + " unmatched pairs (" +
                               std::to_string(ours.size()) + " ours, " + std::to_string(theirs.size()) + " TTK's)";
      std::remove(csv.c_str());
    }
  }
  std::remove(raw.c_str());
  rmdir(dir);
  if (!error.empty()) {
    r.ok = 0;
    std::snprintf(r.error, sizeof r.error, "%s", error.c_str());
  }
  return r;
}

// Runs `measure` in a child process and returns its result through a pipe.
Result measure_in_child(const std::string& field, int n, int runs, int threads, bool phat = false) {
  int fd[2];
  if (pipe(fd) != 0) {
    std::perror("pipe");
    std::exit(1);
  }
  std::fflush(stdout);
  pid_t pid = fork();
  if (pid < 0) {
    std::perror("fork");
    std::exit(1);
  }
  if (pid == 0) {
    close(fd[0]);
    Result r;
    try {
      std::unique_ptr<tbb::global_control> limit;
      if (threads > 0)
        limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, size_t(threads));
      r = measure(field, n, runs, phat);
    } catch (const std::exception& e) {
      std::snprintf(r.error, sizeof r.error, "%s", e.what());
    }
    ssize_t w = write(fd[1], &r, sizeof r);
    (void)w;
    close(fd[1]);
    _exit(0);
  }
  close(fd[1]);
  Result r;
  size_t got = 0;
  while (got < sizeof r) {
    ssize_t k = read(fd[0], reinterpret_cast<char*>(&r) + got, sizeof r - got);
    if (k <= 0) break;
    got += size_t(k);
  }
  close(fd[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  if (got != sizeof r) {
    r = Result{};
    std::snprintf(r.error, sizeof r.error, "child died (%s %d)", WIFSIGNALED(status) ? "signal" : "exit",
                  WIFSIGNALED(status) ? WTERMSIG(status) : WEXITSTATUS(status));
  }
  return r;
}

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream in(s);
  std::string item;
  while (std::getline(in, item, ',')) out.push_back(item);
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  chokeloops::restart_with_huge_pages(argv);
  int runs = 5, threads = 0, peer_max = 0;
  std::string cubicalripser, ttk;
  int ttk_compare_max = 128;
  bool large = false;
  std::vector<int> sizes{128, 256};
  std::vector<std::string> fields{"torus", "noise", "random"};
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--runs") runs = std::max(1, std::atoi(value().c_str()));
    else if (a == "--large") large = true;
    else if (a == "--peer-phat") peer_max = std::atoi(value().c_str());
    else if (a == "--peer-cubicalripser") cubicalripser = value();
    else if (a == "--peer-ttk") ttk = value();
    else if (a == "--peer-ttk-compare") ttk_compare_max = std::atoi(value().c_str());
    else if (a == "--threads") threads = std::atoi(value().c_str());
    else if (a == "--sizes") {
      sizes.clear();
      for (auto& s : split(value())) sizes.push_back(std::atoi(s.c_str()));
    } else if (a == "--fields") fields = split(value());
    else {
      std::fprintf(stderr,
                   "usage: bench_persistence [--runs R] [--large] [--sizes 128,256] [--fields torus,noise,random] "
                   "[--threads N] [--peer-phat MAX_N] [--peer-cubicalripser BIN] [--peer-ttk BIN] "
                   "[--peer-ttk-compare MAX_N]\n");
      return a == "-h" || a == "--help" ? 0 : 2;
    }
  }
  if (large && std::find(sizes.begin(), sizes.end(), 512) == sizes.end()) sizes.push_back(512);

  std::printf("lower_star_persistence: median of %d runs, %d threads (tbb default %d); peak RSS per configuration "
              "(fresh process, includes the float field)\n\n",
              runs, threads > 0 ? threads : tbb::info::default_concurrency(), tbb::info::default_concurrency());
  std::printf("| field | n | classify s | dim0 s | dim2 s | dim1 s | total s | wall s | pairs dim0 | dim1 | dim2 | "
              "joins | splits | peak RSS MB | guard's estimate MB |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  std::fflush(stdout);
  int failures = 0;
  for (int n : sizes)
    for (auto& f : fields) {
      Result r = measure_in_child(f, n, runs, threads);
      if (!r.ok) {
        std::printf("| %s | %d^3 | failed: %s |\n", field_label(f), n, r.error);
        ++failures;
      } else {
        std::printf("| %s | %d^3 | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %lld | %lld | %lld | %lld | %lld | %.0f | %.0f |\n",
                    field_label(f), n, r.classify, r.dim0, r.dim2, r.dim1, r.total, r.wall, r.pairs[0], r.pairs[1],
                    r.pairs[2], r.join_saddles, r.split_saddles, r.peak_rss_mb, r.estimate_mb);
      }
      std::fflush(stdout);
      if (!cubicalripser.empty() && r.ok) {
        Result c = measure_cubicalripser(cubicalripser, f, n, std::min(runs, 3));
        if (!c.ok) {
          std::printf("| CubicalRipser | %d^3 | failed: %s |\n", n, c.error);
          ++failures;
        } else {
          std::printf("| CubicalRipser (1 thread, cubical complex): %s | %d^3 | | | | | | %.3f (%.1fx chokeloops) | | | | | | %.0f (%.1fx) |\n",
                      field_label(f), n, c.wall, c.wall / r.wall, c.peak_rss_mb, c.peak_rss_mb / r.peak_rss_mb);
        }
        std::fflush(stdout);
      }
      if (!ttk.empty() && r.ok) {
        std::string verdict;
        Result c = measure_ttk(ttk, f, n, std::min(runs, 3), threads, n <= ttk_compare_max, verdict);
        if (!c.ok) {
          std::printf("| TTK DiscreteMorseSandwich | %d^3 | failed: %s |\n", n, c.error);
          ++failures;
        } else {
          std::printf("| TTK DiscreteMorseSandwich (%s threads, field mirrored along x): %s | %d^3 | | | | | | %.3f (%.1fx "
                      "chokeloops) | | | | | | %.0f (%.1fx) |\n",
                      threads > 0 ? std::to_string(threads).c_str() : "default", field_label(f), n, c.wall,
                      c.wall / r.wall, c.peak_rss_mb, c.peak_rss_mb / r.peak_rss_mb);
          if (!verdict.empty()) std::printf("  %s\n", verdict.c_str());
          if (verdict.rfind("DIAGRAMS DIFFER", 0) == 0) ++failures;
        }
        std::fflush(stdout);
      }
      if (n > peer_max || !r.ok) continue;
      Result p = measure_in_child(f, n, std::min(runs, 3), threads, true);
      if (!p.ok) {
        std::printf("| PHAT twist, explicit complex | %d^3 | failed: %s |\n", n, p.error);
        ++failures;
        continue;
      }
      std::printf("| PHAT twist, explicit complex: %s | %d^3 | | | | | %.3f | %.3f (%.0fx chokeloops) | %lld | %lld | %lld | | | %.0f |\n",
                  field_label(f), n, p.total, p.wall, p.wall / r.wall, p.pairs[0], p.pairs[1], p.pairs[2], p.peak_rss_mb);
      if (p.pairs[0] != r.pairs[0] || p.pairs[1] != r.pairs[1] || p.pairs[2] != r.pairs[2]) {
        std::printf("  pair counts differ from chokeloops'\n");
        ++failures;
      }
      std::fflush(stdout);
    }
  return failures ? 1 : 0;
}
