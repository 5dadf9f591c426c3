#pragma once
// Scratch directories and files for the tests: one directory per test and process under the system's temp dir.
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace chokeloops::test {

// <temp>/chokeloops_<stem>_<pid>, created.
inline std::filesystem::path temp_dir(const std::string& stem) {
  std::filesystem::path d = std::filesystem::temp_directory_path() / ("chokeloops_" + stem + "_" + std::to_string(::getpid()));
  std::filesystem::create_directories(d);
  return d;
}

// Writes `bytes` to dir/name; returns its path.
inline std::string write_file(const std::filesystem::path& dir, const std::string& name, const std::string& bytes) {
  std::ofstream(dir / name, std::ios::binary) << bytes;
  return (dir / name).string();
}

}  // namespace chokeloops::test
