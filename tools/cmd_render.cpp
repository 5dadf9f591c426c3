// `chokeloops view OUTDIR` (re)writes OUTDIR/view.html; `chokeloops render OUTDIR -o FILE.png` draws it headlessly.
#include <iostream>
#include <string>
#include <vector>

#include "chokeloops/grid.h"
#include "chokeloops/view.h"
#include "command.h"

using namespace chokeloops;

namespace {

int parse_int(const std::string& opt, const std::string& v) {
  try {
    std::size_t used = 0;
    int x = std::stoi(v, &used);
    if (used == v.size()) return x;
  } catch (const std::exception&) {
  }
  throw Error(opt + " expects an integer, got '" + v + "'");
}

const char* kRenderHelp =
    "usage: chokeloops render OUTDIR [-o FILE.png] [--width W] [--height H]\n\n"
    "Draws the surface and loops that `chokeloops analyze ... -o OUTDIR` wrote into a PNG, with headless\n"
    "Chromium (Debian package `chromium`; or set CHOKELOOPS_CHROMIUM), from a viewpoint that shows the loops.\n"
    "Writes OUTDIR/view.html first if it is missing or older than loops.json / surface.ply.\n\n"
    "  -o, --output FILE   the picture (default OUTDIR/loops.png)\n"
    "  --width W           pixels (default 1200)\n"
    "  --height H          pixels (default 900)\n";

const char* kViewHelp =
    "usage: chokeloops view OUTDIR [--face-budget N]\n\n"
    "(Re)writes OUTDIR/view.html from OUTDIR/surface.ply and OUTDIR/loops.json: one self-contained page\n"
    "(no network) with the surface, the loops, a table of loops and the persistence diagrams.\n\n"
    "  --face-budget N     decimate the displayed surface above N faces (default 300000)\n";

cli::Register render_cmd("render", "draw OUTDIR's surface and loops into a PNG (headless Chromium)",
                         [](std::vector<std::string> args) -> int {
  std::string outdir, png;
  int width = 1200, height = 900;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= args.size()) throw Error(a + " needs a value (see chokeloops render --help)");
      return args[++i];
    };
    if (a == "-h" || a == "--help") { std::cout << kRenderHelp; return 0; }
    else if (a == "-o" || a == "--output") png = value();
    else if (a == "--width") width = parse_int(a, value());
    else if (a == "--height") height = parse_int(a, value());
    else if (!a.empty() && a[0] == '-') throw Error("unknown option " + a + " (see chokeloops render --help)");
    else if (outdir.empty()) outdir = a;
    else throw Error("unexpected argument " + a + " (see chokeloops render --help)");
  }
  if (outdir.empty()) { std::cerr << kRenderHelp; return 2; }
  if (png.empty()) png = outdir + "/loops.png";
  render_png(outdir, png, width, height);
  std::cout << png << "\n";
  return 0;
});

cli::Register view_cmd("view", "(re)write OUTDIR/view.html, the interactive page of an analysis",
                       [](std::vector<std::string> args) -> int {
  std::string outdir;
  std::size_t budget = kViewFaceBudget;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "-h" || a == "--help") { std::cout << kViewHelp; return 0; }
    else if (a == "--face-budget") {
      if (i + 1 >= args.size()) throw Error("--face-budget needs a value");
      int n = parse_int(a, args[++i]);
      if (n < 100) throw Error("--face-budget must be at least 100");
      budget = std::size_t(n);
    } else if (!a.empty() && a[0] == '-') throw Error("unknown option " + a + " (see chokeloops view --help)");
    else if (outdir.empty()) outdir = a;
    else throw Error("unexpected argument " + a + " (see chokeloops view --help)");
  }
  if (outdir.empty()) { std::cerr << kViewHelp; return 2; }
  write_view_html(outdir, budget);
  std::cout << outdir << "/view.html\n";
  return 0;
});

}  // namespace
