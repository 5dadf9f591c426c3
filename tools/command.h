#pragma once
// Subcommands of the `chokeloops` program register themselves here; each lives in its own tools/cmd_*.cpp.
#include <functional>
#include <string>
#include <vector>

namespace chokeloops::cli {

struct Command {
  std::string name;
  std::string summary;
  std::function<int(std::vector<std::string>)> run;  // arguments after the subcommand name
};

std::vector<Command>& registry();

struct Register {
  Register(std::string name, std::string summary, std::function<int(std::vector<std::string>)> run) {
    registry().push_back({std::move(name), std::move(summary), std::move(run)});
  }
};

}  // namespace chokeloops::cli
