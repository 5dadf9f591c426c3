#include "chokeloops/batch.h"

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <new>
#include <set>
#include <sstream>
#include <thread>

#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include "chokeloops/output/view.h"

namespace chokeloops {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

const char* kStatusFile = "status.json";

json to_json(const BatchItem& it) {
  return json{{"input", it.input},
              {"outdir", it.outdir},
              {"status", it.status},
              {"genus", it.genus},
              {"handle_generators", it.handle_generators},
              {"tunnel_generators", it.tunnel_generators},
              {"handle_chokes", it.handle_chokes},
              {"tunnel_chokes", it.tunnel_chokes},
              {"deepest_loop", it.deepest_loop},
              {"deepest_side", it.deepest_side},
              {"deepest_depth", it.deepest_depth},
              {"most_persistent_loop", it.most_persistent_loop},
              {"most_persistent_side", it.most_persistent_side},
              {"most_persistent", it.most_persistent},
              {"seconds", it.seconds},
              {"exit_code", it.exit_code},
              {"error", it.error},
              {"options", it.options}};
}

BatchItem from_json(const json& j) {
  BatchItem it;
  it.input = j.value("input", "");
  it.outdir = j.value("outdir", "");
  it.status = j.value("status", "failed");
  it.genus = j.value("genus", -1);
  it.handle_generators = j.value("handle_generators", 0);
  it.tunnel_generators = j.value("tunnel_generators", 0);
  it.handle_chokes = j.value("handle_chokes", 0);
  it.tunnel_chokes = j.value("tunnel_chokes", 0);
  it.deepest_loop = j.value("deepest_loop", -1);
  it.deepest_side = j.value("deepest_side", "");
  it.deepest_depth = j.value("deepest_depth", 0.0);
  it.most_persistent_loop = j.value("most_persistent_loop", -1);
  it.most_persistent_side = j.value("most_persistent_side", "");
  it.most_persistent = j.value("most_persistent", 0.0);
  it.seconds = j.value("seconds", 0.0);
  it.exit_code = j.value("exit_code", 0);
  it.error = j.value("error", "");
  it.options = j.value("options", "");
  return it;
}

bool read_status(const std::string& item_dir, BatchItem& item) {
  std::ifstream in(item_dir + "/" + kStatusFile);
  if (!in) return false;
  try {
    item = from_json(json::parse(in));
    return true;
  } catch (const std::exception&) {
    return false;  // torn or edited by hand: analysed again
  }
}

// Written last, through a temporary file: a status.json present means the directory is complete.
void write_status(const BatchItem& item) {
  std::error_code ec;
  fs::create_directories(item.outdir, ec);
  const std::string path = item.outdir + "/" + kStatusFile, tmp = path + ".tmp";
  {
    std::ofstream out(tmp);
    out << to_json(item).dump(1) << "\n";
    if (!out) return;
  }
  fs::rename(tmp, path, ec);
}

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) {
    if (c == '"') q += '"';
    q += c;
  }
  return q + "\"";
}

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

int default_threads(const BatchOptions& options) {
  if (options.threads > 0) return options.threads;
  int cores = int(std::max(1u, std::thread::hardware_concurrency()));
  return std::max(1, cores / std::max(1, options.jobs));
}

}  // namespace

const std::vector<std::string>& batch_columns() {
  static const std::vector<std::string> columns = {
      "input", "status", "outdir", "genus", "handle_generators", "tunnel_generators", "handle_chokes",
      "tunnel_chokes", "deepest_loop", "deepest_side", "deepest_depth", "most_persistent_loop",
      "most_persistent_side", "most_persistent", "seconds", "resumed", "exit_code", "error"};
  return columns;
}

std::vector<std::string> batch_item_dirs(const std::vector<std::string>& inputs, const std::string& outdir) {
  std::map<std::string, int> stem_count;
  for (auto& in : inputs) stem_count[fs::path(in).stem().string()] += 1;
  std::set<std::string> used;
  std::vector<std::string> dirs;
  for (auto& in : inputs) {
    fs::path p(in);
    std::string name = p.stem().string();
    if (name.empty() || name == "." || name == "..") name = "input";
    if (stem_count[p.stem().string()] > 1 && p.has_extension()) name += "_" + p.extension().string().substr(1);
    std::string unique = name;
    for (int k = 2; used.count(unique); ++k) unique = name + "-" + std::to_string(k);
    used.insert(unique);
    dirs.push_back((fs::path(outdir) / unique).string());
  }
  return dirs;
}

std::string options_key(const AnalyzeOptions& o) {
  std::ostringstream s;
  s.precision(17);
  s << "resolution=" << (o.resolution_auto ? std::string("auto") : std::to_string(o.levelset.resolution))
    << " voxel_size=" << o.levelset.voxel_size << " margin=" << o.levelset.margin << " iso=" << o.levelset.iso
    << " grid=" << o.levelset.grid_name << " fill_holes=" << o.levelset.fill_holes
    << " dmax=" << o.chokes.d_max.text() << " min_persistence=" << o.chokes.min_persistence.text()
    << " handles=" << o.chokes.handles << " tunnels=" << o.chokes.tunnels << " shorten=" << o.loops.shorten
    << " slide=" << o.loops.slide << " plane_start=" << o.loops.plane_start << " check=" << o.check_generators;
  return s.str();
}

bool read_finished_item(const std::string& item_dir, const std::string& key, BatchItem& item) {
  BatchItem it;
  if (!read_status(item_dir, it) || it.status != "ok" || it.options != key) return false;
  if (!fs::exists(item_dir + "/loops.json")) return false;
  it.outdir = item_dir;
  it.resumed = true;
  item = it;
  return true;
}

BatchItem analyze_item(const std::string& input, const std::string& item_dir, const BatchOptions& options) {
  const std::string key = options_key(options.analyze);
  BatchItem item;
  if (options.resume && read_finished_item(item_dir, key, item)) {
    item.input = input;
    return item;
  }
  item.input = input;
  item.outdir = item_dir;
  item.options = key;
  std::error_code ec;
  fs::remove(item_dir + "/" + kStatusFile, ec);  // a crash from here on leaves the directory unfinished
  auto t0 = std::chrono::steady_clock::now();
  try {
    std::unique_ptr<tbb::global_control> limit;
    if (options.threads > 0)
      limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                    std::size_t(options.threads));
    AnalyzeOptions ao = options.analyze;
    ao.levelset.quiet = true;
    AnalyzeResult r = analyze(input, ao);
    write_report(r, ao, item_dir);
    if (options.view) write_view_html(item_dir);
    item.status = "ok";
    item.genus = r.surface_stats.genus;
    for (std::size_t i = 0; i < r.loops.size(); ++i) {
      const Loop& l = r.loops[i];
      const bool tunnel = l.choke.side == Side::Tunnel, generator = l.choke.kind == Kind::Generator;
      (tunnel ? (generator ? item.tunnel_generators : item.tunnel_chokes)
              : (generator ? item.handle_generators : item.handle_chokes)) += 1;
      if (!l.found) continue;
      if (item.deepest_loop < 0 || l.choke.depth > item.deepest_depth) {
        item.deepest_loop = int(i);
        item.deepest_side = to_string(l.choke.side);
        item.deepest_depth = l.choke.depth;
      }
      if (item.most_persistent_loop < 0 || l.choke.persistence > item.most_persistent) {
        item.most_persistent_loop = int(i);
        item.most_persistent_side = to_string(l.choke.side);
        item.most_persistent = l.choke.persistence;
      }
    }
  } catch (const Error& e) {
    item.status = "failed";
    item.exit_code = e.exit_code;
    item.error = e.what();
  } catch (const InternalError& e) {
    item.status = "failed";
    item.exit_code = kInternalErrorExitCode;
    item.error = std::string("internal error (a bug in chokeloops, not a problem with the input): ") + e.what();
  } catch (const std::bad_alloc&) {
    item.status = "failed";
    item.exit_code = 3;
    item.error = "out of memory; use a coarser --resolution";
  } catch (const std::exception& e) {
    item.status = "failed";
    item.exit_code = 2;
    item.error = e.what();
  }
  item.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  write_status(item);
  return item;
}

std::vector<BatchItem> run_batch(const std::vector<std::string>& inputs, const std::string& outdir,
                                 const BatchOptions& options,
                                 const std::function<void(const BatchItem&, std::size_t, std::size_t)>& on_item) {
  std::error_code ec;
  fs::create_directories(outdir, ec);
  if (ec || !fs::is_directory(outdir)) throw Error("cannot create output directory '" + outdir + "': " + ec.message());
  const std::vector<std::string> dirs = batch_item_dirs(inputs, outdir);
  const std::string key = options_key(options.analyze);
  std::vector<BatchItem> items(inputs.size());
  std::size_t done = 0;
  auto finish = [&](std::size_t i) {
    if (on_item) on_item(items[i], ++done, inputs.size());
  };
  std::vector<std::size_t> pending;
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    if (options.resume && read_finished_item(dirs[i], key, items[i])) {
      items[i].input = inputs[i];
      finish(i);
    } else {
      pending.push_back(i);
    }
  }
  // A pool of forked processes: each analyses one input and leaves its status.json; the parent starts no
  // threads of its own, so forking is safe, and a crash or an out-of-memory kill is that input's failure only.
  BatchOptions child_options = options;
  child_options.threads = default_threads(options);
  child_options.resume = false;
  const std::size_t jobs = std::size_t(std::max(1, options.jobs));
  std::map<pid_t, std::size_t> running;
  std::map<pid_t, std::chrono::steady_clock::time_point> started;
  std::size_t next = 0;
  while (next < pending.size() || !running.empty()) {
    while (next < pending.size() && running.size() < jobs) {
      const std::size_t i = pending[next++];
      fs::remove(dirs[i] + "/" + kStatusFile, ec);  // what the child leaves is this run's
      std::fflush(nullptr);
      pid_t pid = fork();
      if (pid < 0) {  // no process to spare: analyse it here
        items[i] = analyze_item(inputs[i], dirs[i], child_options);
        finish(i);
        continue;
      }
      if (pid == 0) {
        analyze_item(inputs[i], dirs[i], child_options);
        std::fflush(nullptr);
        _exit(0);
      }
      running[pid] = i;
      started[pid] = std::chrono::steady_clock::now();
    }
    if (running.empty()) continue;
    int wstatus = 0;
    pid_t pid = waitpid(-1, &wstatus, 0);
    if (pid < 0) {
      if (errno == EINTR) continue;
      throw Error(std::string("batch: waitpid failed: ") + std::strerror(errno), 3);
    }
    auto found = running.find(pid);
    if (found == running.end()) continue;
    const std::size_t i = found->second;
    running.erase(found);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started[pid]).count();
    started.erase(pid);
    BatchItem it;
    const bool reported = read_status(dirs[i], it) && it.options == key;
    if (!reported) {  // the child died before writing its status: a crash (a bug) or a kill (memory?)
      it = BatchItem{};
      it.status = "failed";
      it.exit_code = kInternalErrorExitCode;
      it.seconds = seconds;
      it.options = key;
      if (WIFSIGNALED(wstatus)) {
        const int sig = WTERMSIG(wstatus);
        it.error = "the analysis crashed (signal " + std::to_string(sig) + ", " + strsignal(sig) + ")";
        if (sig == SIGKILL) {
          it.exit_code = 3;
          it.error += "; killed, perhaps out of memory: try a coarser --resolution or fewer --jobs";
        }
      } else {
        it.error = "the analysis ended (exit code " + std::to_string(WEXITSTATUS(wstatus)) + ") without a status";
      }
    }
    it.input = inputs[i];
    it.outdir = dirs[i];
    items[i] = it;
    if (!reported) write_status(items[i]);
    finish(i);
  }
  write_batch_summary(items, (fs::path(outdir) / "summary.csv").string());
  return items;
}

void write_batch_summary(const std::vector<BatchItem>& items, const std::string& csv_path) {
  const std::string tmp = csv_path + ".tmp";
  {
    std::ofstream out(tmp);
    if (!out) throw Error("cannot write '" + csv_path + "'");
    const auto& cols = batch_columns();
    for (std::size_t c = 0; c < cols.size(); ++c) out << (c ? "," : "") << cols[c];
    out << "\n";
    for (auto& it : items) {
      const bool ok = it.status == "ok";
      auto opt_int = [&](int v) { return ok ? std::to_string(v) : std::string(); };
      auto loop_id = [&](int v) { return v >= 0 ? std::to_string(v) : std::string(); };
      std::vector<std::string> f = {
          csv_field(it.input), it.status, csv_field(it.outdir), opt_int(it.genus),
          opt_int(it.handle_generators), opt_int(it.tunnel_generators), opt_int(it.handle_chokes),
          opt_int(it.tunnel_chokes), loop_id(it.deepest_loop), it.deepest_side,
          it.deepest_loop >= 0 ? number(it.deepest_depth) : "", loop_id(it.most_persistent_loop),
          it.most_persistent_side, it.most_persistent_loop >= 0 ? number(it.most_persistent) : "",
          number(it.seconds), it.resumed ? "1" : "0", std::to_string(it.exit_code), csv_field(it.error)};
      for (std::size_t c = 0; c < f.size(); ++c) out << (c ? "," : "") << f[c];
      out << "\n";
    }
    if (!out) throw Error("cannot write '" + csv_path + "' (disk full?)");
  }
  std::error_code ec;
  fs::rename(tmp, csv_path, ec);
  if (ec) throw Error("cannot write '" + csv_path + "': " + ec.message());
}

}  // namespace chokeloops
