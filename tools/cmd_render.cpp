// `chokeloops view OUTDIR` (re)writes OUTDIR/view.html; `chokeloops render OUTDIR -o FILE.png` draws it headlessly.
#include <iostream>
#include <string>
#include <vector>

#include "chokeloops/grid.h"
#include "chokeloops/output/view.h"
#include "args.h"
#include "command.h"

using namespace chokeloops;

namespace {

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
  cli::Args in("render", std::move(args));
  while (in.next()) {
    if (in.is("-h", "--help")) { std::cout << kRenderHelp; return 0; }
    else if (in.is("-o", "--output")) png = in.value();
    else if (in.is("--width")) width = int(in.integer(16, 16384));
    else if (in.is("--height")) height = int(in.integer(16, 16384));
    else in.positional(outdir, "OUTDIR");
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
  cli::Args in("view", std::move(args));
  while (in.next()) {
    if (in.is("-h", "--help")) { std::cout << kViewHelp; return 0; }
    else if (in.is("--face-budget")) budget = std::size_t(in.integer(100, 1000000000));
    else in.positional(outdir, "OUTDIR");
  }
  if (outdir.empty()) { std::cerr << kViewHelp; return 2; }
  write_view_html(outdir, budget);
  std::cout << outdir << "/view.html\n";
  return 0;
});

}  // namespace
