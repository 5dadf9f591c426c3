#include "args.h"

#include <cmath>
#include <cstdlib>

#include "chokeloops/grid.h"

namespace chokeloops::cli {

std::vector<std::string> split_list(const std::string& value) {
  std::vector<std::string> out;
  std::string cur;
  for (char c : value + ",") {
    if (c == ',') {
      if (!cur.empty()) out.push_back(cur);
      cur.clear();
    } else if (c != ' ') {
      cur += c;
    }
  }
  return out;
}

std::string Args::value() {
  if (i_ + 1 >= args_.size()) throw Error("option " + arg() + " needs a value (" + see_help() + ")");
  return args_[++i_];
}

double Args::number() {
  const std::string& option = arg();
  std::string v = value();
  char* end = nullptr;
  double x = std::strtod(v.c_str(), &end);
  if (v.empty() || *end || !std::isfinite(x))
    throw Error("option " + option + " expects a number, got '" + v + "' (" + see_help() + ")");
  return x;
}

long Args::integer(long lo, long hi) {
  const std::string& option = arg();
  std::string v = value();
  char* end = nullptr;
  long x = std::strtol(v.c_str(), &end, 10);
  if (v.empty() || *end || x < lo || x > hi)
    throw Error("option " + option + " expects an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                "], got '" + v + "'");
  return x;
}

void Args::positional(std::string& slot, const char* what) {
  const std::string& a = arg();
  if (a.size() > 1 && a[0] == '-') throw Error("unknown option " + a + " (" + see_help() + ")");
  if (!slot.empty()) throw Error("more than one " + std::string(what) + " given ('" + slot + "' and '" + a + "')");
  slot = a;
}

std::unique_ptr<tbb::global_control> limit_threads(int n) {
  if (n <= 0) return nullptr;
  return std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, std::size_t(n));
}

}  // namespace chokeloops::cli
