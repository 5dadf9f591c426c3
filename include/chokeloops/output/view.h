#pragma once
// Seeing the loops: OUTDIR/view.html (one self-contained interactive page: surface, loops, table, persistence
// diagrams; three.js is inlined, no network) and a PNG of it rendered by headless Chromium.
// Both read what `analyze` wrote: OUTDIR/surface.ply and OUTDIR/loops.json (DESIGN.md section 5).
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace chokeloops {

// Surfaces with more faces than this are decimated (vertex clustering) for display; the page says so.
inline constexpr std::size_t kViewFaceBudget = 300000;

// Reads OUTDIR/surface.ply and OUTDIR/loops.json and writes OUTDIR/view.html.
// Surfaces above face_budget faces are decimated for display (0: never). Throws Error (exit code 2) when an
// input is missing or malformed.
void write_view_html(const std::string& outdir, std::size_t face_budget = kViewFaceBudget);

// Renders OUTDIR/view.html (written first if missing or older than its inputs) with headless Chromium into png_path, from the default
// viewpoint (loops seen face-on, drawn over the surface where hidden). Throws Error when Chromium is
// missing (install Debian's `chromium`, or set CHOKELOOPS_CHROMIUM to a Chrome/Chromium binary), when an
// input is missing, or when Chromium fails to write the picture.
void render_png(const std::string& outdir, const std::string& png_path, int width = 1200, int height = 900);

// Path of the Chromium binary render_png would use ($CHOKELOOPS_CHROMIUM, else chromium, chromium-browser,
// google-chrome on PATH), or "" if there is none: lets callers skip --png with a warning instead of failing.
std::string find_chromium();

// The command-line flags render_png passes to Chromium besides the URL, --screenshot and --user-data-dir.
std::vector<std::string> chromium_flags(int width, int height);

namespace view_detail {
// Exposed for tests.
struct TriMesh {
  std::vector<std::array<float, 3>> vertices;
  std::vector<std::array<std::uint32_t, 3>> faces;
};
// Reads x,y,z of `vertex` and the `vertex_indices` (or `vertex_index`) lists of `face` from an ascii or
// binary (either endianness) PLY; polygons are fanned into triangles. Throws Error on malformed files.
TriMesh read_ply(const std::string& path);
// Vertex clustering on a uniform grid, coarsened until at most max_faces faces remain; returns the cell size
// used (0 when the mesh already fits). Degenerate and duplicate faces are dropped.
double decimate(TriMesh& mesh, std::size_t max_faces);
}  // namespace view_detail

}  // namespace chokeloops
