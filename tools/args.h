#pragma once
// One reader for every subcommand's arguments, so that options, numbers, thread counts and positionals are
// checked and worded alike: each mistake is a chokeloops::Error naming the option and `chokeloops CMD --help`.
#include <memory>
#include <string>
#include <vector>

#include <tbb/global_control.h>

namespace chokeloops::cli {

// The items of a comma-separated option value, spaces and empty items dropped ("A, B,,C" -> A B C).
std::vector<std::string> split_list(const std::string& value);

class Args {
 public:
  Args(std::string command, std::vector<std::string> args) : command_(std::move(command)), args_(std::move(args)) {}

  // Moves to the next argument; false when there is none left.
  bool next() { return ++i_ < args_.size(); }
  const std::string& arg() const { return args_[i_]; }
  bool is(const char* name, const char* alias = nullptr) const { return arg() == name || (alias && arg() == alias); }

  // The argument after the current one, without moving ("" if none).
  std::string peek() const { return i_ + 1 < args_.size() ? args_[i_ + 1] : std::string(); }
  // The current option's value (the next argument).
  std::string value();
  // value() as a finite number / as an integer in [lo, hi].
  double number();
  long integer(long lo, long hi);
  // value() as a thread count: a positive integer.
  int threads() { return int(integer(1, 4096)); }
  // The current argument as a positional: an unknown option is refused, and so is a second `slot`.
  void positional(std::string& slot, const char* what);

  // "see chokeloops CMD --help", for messages the caller words itself.
  std::string see_help() const { return "see chokeloops " + command_ + " --help"; }

 private:
  std::string command_;
  std::vector<std::string> args_;
  std::size_t i_ = std::size_t(-1);
};

// Limits TBB to n threads while the returned object lives; n <= 0 leaves the default (all cores).
std::unique_ptr<tbb::global_control> limit_threads(int n);

}  // namespace chokeloops::cli
