#pragma once
// Cutting the user's mesh along input loops (input_loops.h) and capping each cut: the edges of every loop are
// duplicated (CGAL PMP's split along edges) and each border cycle this opens is closed by CGAL's
// triangulate_hole, so a cut along a handle's generator lowers the genus by one and leaves every other
// triangle as it was.
#include <string>
#include <vector>

#include "chokeloops/io/mesh_io.h"

namespace chokeloops {

struct CutResult {
  TriangleMesh mesh;        // the input's faces first, in their order (corners on a cut renumbered), then the caps
  MeshReport before, after;  // mesh_topology of the input and of the result
  int loops_cut = 0;
  int caps = 0;             // border cycles closed
  int cap_faces = 0;
  std::vector<std::string> notes;  // loops left uncut, and why (one that crosses an earlier cut)
};

// `loops`: closed edge paths (cyclic vertex lists, first vertex not repeated) on `mesh`, cut in turn (a loop
// that touches an earlier one follows the earlier cut's vertex copies). Throws Error when a
// loop is not a path of mesh edges, repeats a vertex (only simple loops are cut) or the mesh is not an
// orientable manifold that CGAL's Surface_mesh accepts.
// Messages name loop i by ids[i] when given (input_loops.json's ids), else by i.
CutResult cut_along_loops(const TriangleMesh& mesh, const std::vector<std::vector<int>>& loops,
                          const std::vector<int>& ids = {});

// What `chokeloops cut` selects: explicit loop ids, or every verified generator of a side.
struct CutSelection {
  std::vector<int> ids;     // non-empty: exactly these loops of input_loops.json
  bool handles = true;      // otherwise: the verified generators of this side (handle by default)
};

// The command behind `chokeloops cut INPUT OUTDIR -o OUTPUT`: reads OUTDIR/input_loops.json (written by
// analyze for INPUT), loads INPUT as that file says, cuts along the selected loops and writes OUTPUT
// (.off .ply .obj .stl). Throws Error (2) for a missing or mismatched report, an unknown or unusable id.
CutResult cut_mesh_file(const std::string& input, const std::string& outdir, const std::string& output,
                        const CutSelection& selection, std::vector<int>* cut_ids = nullptr);

}  // namespace chokeloops
