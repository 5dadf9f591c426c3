#pragma once
// Batch analysis: many inputs, one output directory each, one summary CSV. Resumable (an input whose
// directory holds a successful status.json made with the same options is skipped) and a failing input never
// stops the others. `chokeloops batch` and chokeloops.batch() in Python (which can also run the items on a
// Dask cluster) are thin layers over this.
#include <functional>
#include <string>
#include <vector>

#include "chokeloops/analyze.h"

namespace chokeloops {

struct BatchOptions {
  AnalyzeOptions analyze;
  int jobs = 1;        // inputs analysed at once, each in its own forked process (run_batch only)
  int threads = 0;     // TBB threads per item; 0: all cores divided by jobs
  bool resume = true;  // skip inputs that finished with the same options; false: analyse everything again
  bool view = true;    // also write view.html into each input's directory
};

// One input's line of the summary, also kept as OUTDIR/<item>/status.json.
struct BatchItem {
  std::string input;         // as given
  std::string outdir;        // this input's output directory
  std::string status;        // "ok" or "failed"
  bool resumed = false;      // read back from an earlier run's status.json instead of analysed
  int genus = -1;            // of the extracted surface; -1 when failed
  int handle_generators = 0, tunnel_generators = 0, handle_chokes = 0, tunnel_chokes = 0;
  int deepest_loop = -1;               // id in loops.json of the deepest loop found; -1 none
  std::string deepest_side;            // "handle" / "tunnel" / ""
  double deepest_depth = 0;
  int most_persistent_loop = -1;       // id in loops.json of the most persistent loop found; -1 none
  std::string most_persistent_side;
  double most_persistent = 0;          // its persistence
  double seconds = 0;                  // wall time of the analysis and the report
  int exit_code = 0;                   // the CLI's: 0 ok, 2 bad input, 3 out of resources, 4 internal error or crash
  std::string error;                   // the message the CLI would print ("" when ok)
  std::string options;                 // options_key() of the run
};

// The summary's columns, in order (the CSV header).
const std::vector<std::string>& batch_columns();

// One output directory per input under `outdir`: the input's file name without its extension, made unique
// (name_ext, then a -2, -3 ... suffix) when two inputs share it. Deterministic in the order of `inputs`.
std::vector<std::string> batch_item_dirs(const std::vector<std::string>& inputs, const std::string& outdir);

// The settings that change an analysis's results, as text: resume skips an input only when they match.
std::string options_key(const AnalyzeOptions& options);

// A finished earlier run of `item_dir` with these options ("ok" status.json), if any.
bool read_finished_item(const std::string& item_dir, const std::string& key, BatchItem& item);

// Analyses one input into item_dir (report files, view.html, status.json); never throws: any error becomes
// a "failed" item with the CLI's message. With options.resume, a finished earlier run is returned instead.
BatchItem analyze_item(const std::string& input, const std::string& item_dir, const BatchOptions& options);

// Every input, options.jobs at a time (forked processes: a crash in one input is its own failure), then
// OUTDIR/summary.csv. `on_item` is called in the parent as each input finishes (or is skipped).
std::vector<BatchItem> run_batch(const std::vector<std::string>& inputs, const std::string& outdir,
                                 const BatchOptions& options,
                                 const std::function<void(const BatchItem&, std::size_t done, std::size_t total)>& on_item = {});

// Writes the summary CSV (RFC 4180 quoting), header batch_columns(); atomically (temporary + rename).
void write_batch_summary(const std::vector<BatchItem>& items, const std::string& csv_path);

}  // namespace chokeloops
