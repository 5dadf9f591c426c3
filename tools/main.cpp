// The `chokeloops` program: a thin dispatcher over the subcommands in tools/cmd_*.cpp.
#include <algorithm>
#include <exception>
#include <iostream>

#include "chokeloops/grid.h"
#include "chokeloops/huge_pages.h"
#include "command.h"

namespace chokeloops::cli {
std::vector<Command>& registry() {
  static std::vector<Command> commands;
  return commands;
}
}  // namespace chokeloops::cli

using namespace chokeloops;

static void usage(std::ostream& out) {
  auto cmds = cli::registry();
  std::sort(cmds.begin(), cmds.end(), [](auto& a, auto& b) { return a.name < b.name; });
  out << "chokeloops " << CHOKELOOPS_VERSION << " - choking loops of 3D shapes\n\n"
      << "usage: chokeloops COMMAND [ARGS...]   (chokeloops COMMAND --help for its options)\n\ncommands:\n";
  for (auto& c : cmds) out << "  " << c.name << std::string(14 - std::min<size_t>(13, c.name.size()), ' ') << c.summary << "\n";
}

int main(int argc, char** argv) {
  restart_with_huge_pages(argv);
  if (argc < 2) { usage(std::cerr); return 2; }
  std::string name = argv[1];
  if (name == "--help" || name == "-h" || name == "help") { usage(std::cout); return 0; }
  if (name == "--version" || name == "-V") { std::cout << "chokeloops " << CHOKELOOPS_VERSION << "\n"; return 0; }
  for (auto& c : cli::registry()) {
    if (c.name != name) continue;
    try {
      return c.run(std::vector<std::string>(argv + 2, argv + argc));
    } catch (const Error& e) {
      std::cerr << "chokeloops " << name << ": error: " << e.what() << "\n";
      return e.exit_code;
    } catch (const InternalError& e) {
      std::string command_line = "chokeloops";
      for (int i = 1; i < argc; ++i) command_line += std::string(" ") + argv[i];
      std::cerr << "chokeloops " << name << ": internal error (a bug in chokeloops, not a problem with the input): "
                << e.what() << "; please report it with the input file and the command line `" << command_line
                << "`\n";
      return kInternalErrorExitCode;
    } catch (const std::bad_alloc&) {
      std::cerr << "chokeloops " << name << ": error: out of memory; use a coarser --resolution\n";
      return 3;
    } catch (const std::exception& e) {
      std::cerr << "chokeloops " << name << ": error: " << e.what() << "\n";
      return 2;
    }
  }
  std::cerr << "chokeloops: unknown command '" << name << "' (try chokeloops --help)\n";
  return 2;
}
