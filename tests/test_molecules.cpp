// Molecules: gramicidin A against HOLE's published bottleneck, analytic pores (a ring of atoms,
// a cylindrical hole through a slab of atoms), and the bad-input cases of the molecule reader.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <zlib.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include <Eigen/Dense>

#include <tbb/global_control.h>

#include "temp_dir.h"
#include "chokeloops/analyze_molecule.h"
#include "chokeloops/loops/channels.h"
#include "chokeloops/loops/shorten.h"
#include "chokeloops/surface/topology.h"

namespace fs = std::filesystem;
using namespace chokeloops;

namespace {

const std::string kData = CHOKELOOPS_DATA;

MolAtom atom(double x, double y, double z, double r, int resseq) {
  MolAtom a;
  a.pos = {x, y, z};
  a.radius = r;
  a.element = "C";
  a.name = "C";
  a.resname = "RNG";
  a.chain = "A";
  a.resseq = resseq;
  return a;
}

// The engine on a molecule built in memory (no file): field, persistence, chokes, surface, channels.
struct MolRun {
  AnalyzeResult r;
  std::vector<Channel> channels;
};
MolRun run(const Molecule& mol, double h) {
  MolecularFieldOptions fo;
  fo.voxel_size = h;
  MolRun out;
  out.r = analyze_grid(molecular_field(mol, fo), AnalyzeOptions{});
  std::vector<std::array<double, 3>> c;
  std::vector<double> rad;
  for (auto& a : mol.atoms) c.push_back(a.pos), rad.push_back(a.radius);
  AtomLocator loc(c, rad);
  out.channels = analyze_channels(out.r.grid, out.r.surface, loc, loc, out.r.chokes.chokes);
  return out;
}

const Channel* widest(const std::vector<Channel>& ch) {
  const Channel* best = nullptr;
  for (auto& c : ch)
    if (!best || c.bottleneck_radius > best->bottleneck_radius) best = &c;
  return best;
}

}  // namespace

// Eight atoms of radius 1.7 on a circle of radius 3: the largest ball through the ring has radius 3 - 1.7,
// centred on the ring's axis, and the axis is the ring's normal.
TEST(MoleculeAnalytic, RingOfAtoms) {
  Molecule mol;
  mol.path = "ring";
  for (int i = 0; i < 8; ++i)
    mol.atoms.push_back(atom(3 * std::cos(i * M_PI / 4), 3 * std::sin(i * M_PI / 4), 0, 1.7, i + 1));
  MolRun r = run(mol, 0.1);
  EXPECT_EQ(r.r.chokes.tunnel_generators, 1);
  const Channel* c = widest(r.channels);
  ASSERT_NE(c, nullptr);
  ASSERT_TRUE(c->refined) << c->note;
  EXPECT_NEAR(c->bottleneck_radius, 1.3, 1e-9);
  EXPECT_NEAR(std::hypot(c->bottleneck[0], c->bottleneck[1], c->bottleneck[2]), 0, 1e-9);
  EXPECT_NEAR(std::abs(c->axis[2]), 1, 1e-9);
  EXPECT_EQ(c->bottleneck_lining.size(), 8u);
  EXPECT_TRUE(c->open[0] && c->open[1]);
  // the profile's narrowest point is the bottleneck; the ring's cross-section is its loop
  double rmin = 1e9;
  for (auto& p : c->profile) rmin = std::min(rmin, p.radius);
  EXPECT_NEAR(rmin, 1.3, 1e-9);
  ASSERT_FALSE(c->section.empty());
  EXPECT_NEAR(c->section_length, 2 * M_PI * 1.3, 0.15 * 2 * M_PI * 1.3);
}

// The same ring with a probe wider than its bottleneck: the bottleneck, axis and lining are still exact, the
// profile and the section are not traced and the note says why.
TEST(MoleculeAnalytic, RingNarrowerThanTheProbeGetsItsBottleneckAndANote) {
  Molecule mol;
  mol.path = "ring";
  for (int i = 0; i < 8; ++i)
    mol.atoms.push_back(atom(3 * std::cos(i * M_PI / 4), 3 * std::sin(i * M_PI / 4), 0, 1.7, i + 1));
  MolecularFieldOptions fo;
  fo.voxel_size = 0.1;
  AnalyzeResult r = analyze_grid(molecular_field(mol, fo), AnalyzeOptions{});
  std::vector<std::array<double, 3>> c;
  std::vector<double> rad;
  for (auto& a : mol.atoms) c.push_back(a.pos), rad.push_back(a.radius);
  AtomLocator loc(c, rad);
  ChannelOptions o;
  o.min_radius = 1.5;
  std::vector<Channel> ch = analyze_channels(r.grid, r.surface, loc, loc, r.chokes.chokes, o);
  const Channel* w = widest(ch);
  ASSERT_NE(w, nullptr);
  EXPECT_NEAR(w->bottleneck_radius, 1.3, 1e-9);
  EXPECT_EQ(w->bottleneck_lining.size(), 8u);
  EXPECT_FALSE(w->traced);
  EXPECT_TRUE(w->profile.empty());
  EXPECT_TRUE(w->section.empty());
  EXPECT_NE(w->note.find("narrower than --min-radius 1.5 A"), std::string::npos) << w->note;
}

// A slab of atoms (radius 1.5, square lattice 2 Å, three layers) with the atoms closer than 4 Å to the z axis
// removed: the pore's bottleneck is on the axis in a layer, 4 - 1.5 = 2.5 Å.
TEST(MoleculeAnalytic, CylindricalPoreThroughASlab) {
  Molecule mol;
  mol.path = "slab";
  int n = 0;
  for (int k = -1; k <= 1; ++k)
    for (int j = -5; j <= 5; ++j)
      for (int i = -5; i <= 5; ++i) {
        const double x = 2.0 * i, y = 2.0 * j;
        if (std::hypot(x, y) < 4.0 - 1e-9) continue;
        mol.atoms.push_back(atom(x, y, 2.0 * k, 1.5, ++n));
      }
  MolRun r = run(mol, 0.2);
  const Channel* c = widest(r.channels);
  ASSERT_NE(c, nullptr);
  ASSERT_TRUE(c->refined) << c->note;
  EXPECT_NEAR(c->bottleneck_radius, 2.5, 1e-9);
  EXPECT_NEAR(std::hypot(c->bottleneck[0], c->bottleneck[1]), 0, 1e-9);
  EXPECT_NEAR(std::abs(c->axis[2]), 1, 1e-9);
  EXPECT_TRUE(c->open[0] && c->open[1]);
  // the path crosses the slab (z from below -3.5 to above 3.5)
  ASSERT_FALSE(c->profile.empty());
  EXPECT_LT(std::min(c->profile.front().p[2], c->profile.back().p[2]), -3.5);
  EXPECT_GT(std::max(c->profile.front().p[2], c->profile.back().p[2]), 3.5);
}

// HOLE's own example, with its radii (simple.rad): HOLE reports a minimum radius of 1.199 Å.
TEST(MoleculeGramicidin, BottleneckAsHoleOnTheAxisWithItsLoopInThePore) {
  AnalyzeOptions ao;
  ao.levelset.voxel_size = 0.2;
  MoleculeOptions mo;
  mo.read.radii = RadiusSet::Amber;
  MoleculeAnalysis m = analyze_molecule(kData + "/molecules/1grm_single_hole2.pdb", ao, mo);
  const Channel* c = widest(m.channels);
  ASSERT_NE(c, nullptr);
  EXPECT_TRUE(c->refined);
  EXPECT_NEAR(c->bottleneck_radius, 1.199, 0.1);
  // the pore axis: the principal axis of the atoms through their centroid
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (auto& a : m.molecule.atoms) mean += Eigen::Vector3d(a.pos[0], a.pos[1], a.pos[2]);
  mean /= double(m.molecule.atoms.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (auto& a : m.molecule.atoms) {
    Eigen::Vector3d d = Eigen::Vector3d(a.pos[0], a.pos[1], a.pos[2]) - mean;
    cov += d * d.transpose();
  }
  Eigen::Vector3d axis = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvectors().col(2);
  Eigen::Vector3d b(c->bottleneck[0], c->bottleneck[1], c->bottleneck[2]);
  Eigen::Vector3d off = (b - mean) - (b - mean).dot(axis) * axis;
  // measured 0.51 Å from this crude axis (the atoms are not symmetric about the pore): inside the lumen's
  // narrowest circle
  EXPECT_LT(off.norm(), c->bottleneck_radius) << "bottleneck " << b.transpose() << " off the pore axis by " << off.norm();
  const Loop& l = m.result.loops[std::size_t(c->loop)];
  ASSERT_TRUE(l.found) << l.note;
  // 2 pi r_b would be the loop of a smooth cylindrical pore; this lumen's wall dips into the grooves between
  // atoms, and its shortest loop around the pore is 12.9 Å (13.1 Å at 0.1 Å voxels): 1.7 x 2 pi r_b.
  const double ring = 2 * M_PI * c->bottleneck_radius;
  EXPECT_LT(l.length, 2.0 * ring);
  EXPECT_GT(l.length, ring);
  // No loop around the pore near the bottleneck is shorter: the surface's cross-sections in planes shifted
  // along the axis and tilted, each shortened as the loop was, are all at least as long (to 1%).
  {
    const MeshAdjacency adjacency = build_adjacency(m.result.surface);
    SurfaceTopology topology(m.result.surface, adjacency);
    const Eigen::Vector3d axis(c->axis[0], c->axis[1], c->axis[2]);
    Eigen::Vector3d e1 = std::abs(axis[0]) < 0.9 ? Eigen::Vector3d(1, 0, 0) : Eigen::Vector3d(0, 1, 0);
    e1 = (e1 - e1.dot(axis) * axis).normalized();
    const Eigen::Vector3d e2 = axis.cross(e1);
    int sections = 0;
    for (double shift = -1.5; shift <= 1.51; shift += 0.5)
      for (int tilt : {0, 20})
        for (int k = 0; k < (tilt ? 4 : 1); ++k) {
          const double t = tilt * M_PI / 180, phi = k * M_PI / 2;
          const Eigen::Vector3d n = std::cos(t) * axis + std::sin(t) * (std::cos(phi) * e1 + std::sin(phi) * e2);
          const Eigen::Vector3d q = b + shift * axis;
          const Polyline3 section = cross_section_loop(m.result.surface, {q[0], q[1], q[2]}, {n[0], n[1], n[2]},
                                                       c->bottleneck_radius + 3.5);
          if (section.empty()) continue;
          ShortenOptions so;
          so.max_move = 2.0;
          const ShortenResult s = shorten_polyline(m.result.surface, adjacency, section, so);
          if (s.points.empty() || topology.null_homologous(s.edge_path)) continue;  // not around the pore
          ++sections;
          EXPECT_GE(std::min(s.length, closed_length(section)), 0.99 * l.length) << "shift " << shift << " tilt " << tilt;
        }
    EXPECT_GE(sections, 6);  // 9 of the 35 planes cut a closed curve around the pore
  }
  double farthest = 0;
  for (auto& p : l.points) {
    Eigen::Vector3d q(p[0], p[1], p[2]);
    farthest = std::max(farthest, (q - b).norm());
  }
  EXPECT_LT(farthest, c->bottleneck_radius + 2.0) << "the loop leaves the pore";
  // every tunnel generator has a loop or says why not; with the default --min-radius (0.9 A) the tunnels
  // between atoms and the rings of atoms closed by contacts get that note
  int narrow = 0, thin = 0;
  for (auto& loop : m.result.loops) {
    if (loop.choke.side == Side::Tunnel && loop.choke.kind == Kind::Generator)
      EXPECT_TRUE(loop.found || !loop.note.empty());
    narrow += loop.note.find("narrower than --min-radius 0.9 A") != std::string::npos;
    thin += loop.note.find("thinner than --min-radius 0.9 A") != std::string::npos;
  }
  EXPECT_GT(narrow, 100);
  EXPECT_GT(thin, 100);
  for (auto& other : m.channels)
    EXPECT_EQ(other.traced, other.bottleneck_radius >= 0.9) << other.bottleneck_radius;
}

// The molecule pipeline builds the surface's adjacency and statistics beside the persistence when its memory
// budget certainly holds both, and after it otherwise; on one thread or two. Every answer is the same.
TEST(MoleculeGramicidin, SurfaceBesideThePersistenceOrAfterItOnAnyThreadCountGivesTheSameResults) {
  auto run = [](std::size_t max_memory, int threads) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
    AnalyzeOptions ao;
    ao.levelset.voxel_size = 0.25;
    ao.levelset.max_memory = max_memory;
    return analyze_molecule(kData + "/molecules/1grm_single_hole2.pdb", ao, MoleculeOptions{});
  };
  // 2.95M voxels: the field's guard needs 24 bytes a voxel + 64 MB (135 MB); overlapping needs the surface,
  // 40 bytes a vertex and a face for its adjacency and statistics, and 48 bytes a voxel: 160 MB runs one
  // after the other.
  const std::size_t tight = std::size_t(160) << 20;
  const MoleculeAnalysis beside = run(0, 2), after = run(tight, 2), one = run(0, 1);
  {
    const AnalyzeResult& a = beside.result;
    const std::size_t voxels = std::size_t(a.grid.dims[0]) * a.grid.dims[1] * a.grid.dims[2];
    const std::size_t v = a.surface.vertices.size(), f = a.surface.faces.size();
    ASSERT_GT(48 * voxels + 24 * v + 12 * f + 40 * (v + f) + (std::size_t(16) << 20), tight);
    ASSERT_GE(tight, 24 * voxels + (std::size_t(64) << 20));
  }
  for (const MoleculeAnalysis* m : {&after, &one}) {
    const AnalyzeResult &a = beside.result, &b = m->result;
    ASSERT_EQ(a.diagram.pairs.size(), b.diagram.pairs.size());
    for (std::size_t i = 0; i < a.diagram.pairs.size(); ++i) {
      ASSERT_EQ(a.diagram.pairs[i].birth_simplex, b.diagram.pairs[i].birth_simplex) << i;
      ASSERT_EQ(a.diagram.pairs[i].death_simplex, b.diagram.pairs[i].death_simplex) << i;
    }
    EXPECT_EQ(a.surface.vertices, b.surface.vertices);
    EXPECT_EQ(a.surface.faces, b.surface.faces);
    EXPECT_EQ(a.surface_stats.genus, b.surface_stats.genus);
    EXPECT_EQ(a.surface_stats.components, b.surface_stats.components);
    EXPECT_EQ(a.surface_stats.component_genus, b.surface_stats.component_genus);
    EXPECT_EQ(a.surface_stats.area, b.surface_stats.area);
    EXPECT_EQ(a.surface_stats.enclosed_volume, b.surface_stats.enclosed_volume);
    ASSERT_EQ(a.loops.size(), b.loops.size());
    int found = 0;
    for (std::size_t i = 0; i < a.loops.size(); ++i) {
      EXPECT_EQ(a.loops[i].found, b.loops[i].found) << i;
      EXPECT_EQ(a.loops[i].points, b.loops[i].points) << i;
      EXPECT_EQ(a.loops[i].note, b.loops[i].note) << i;
      found += a.loops[i].found;
    }
    EXPECT_GT(found, 0);
    ASSERT_EQ(beside.channels.size(), m->channels.size());
    for (std::size_t i = 0; i < beside.channels.size(); ++i)
      EXPECT_EQ(beside.channels[i].bottleneck_radius, m->channels[i].bottleneck_radius) << i;
  }
  EXPECT_GT(beside.result.surface_stats.genus, 50);  // gramicidin's rings of atoms (64 at 0.25 A)
}

TEST(MoleculeInput, ElementsFromAtomNamesWhenColumnsHoldDigits) {
  Molecule m = read_molecule(kData + "/molecules/1grm_single_hole2.pdb");
  ASSERT_FALSE(m.atoms.empty());
  EXPECT_EQ(m.atoms[0].element, "C");
  bool warned = false;
  for (auto& w : m.warnings) warned |= w.find("columns 77-78") != std::string::npos;
  EXPECT_TRUE(warned);
  MoleculeReadOptions amber;
  amber.radii = RadiusSet::Amber;
  EXPECT_DOUBLE_EQ(read_molecule(kData + "/molecules/1grm_single_hole2.pdb", amber).atoms[0].radius, 1.85);
}

TEST(MoleculeInput, WatersAndIonsIgnoredChainsAndModelChosen) {
  const std::string path = kData + "/molecules/1af6_hole2.pdb";
  Molecule all = read_molecule(path);
  for (auto& a : all.atoms) EXPECT_NE(a.resname, "HOH");
  MoleculeReadOptions keep;
  keep.ignore_set = true;
  EXPECT_GT(read_molecule(path, keep).atoms.size(), all.atoms.size());
  MoleculeReadOptions chain_a;
  chain_a.chains = {"A"};
  Molecule a = read_molecule(path, chain_a);
  EXPECT_LT(a.atoms.size(), all.atoms.size());
  for (auto& at : a.atoms) EXPECT_EQ(at.chain, "A");
  MoleculeReadOptions model2;
  model2.model = 2;
  EXPECT_THROW(read_molecule(path, model2), Error);
}

namespace {
struct Outcome {
  int code = -1;
  std::string err;
};
Outcome cli(const std::string& args) {
  const std::string cmd = std::string(CHOKELOOPS_CLI) + " analyze " + args + " 2>&1 1>/dev/null";
  Outcome o;
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) return o;
  char buf[4096];
  std::size_t n;
  while ((n = fread(buf, 1, sizeof buf, p)) > 0) o.err.append(buf, n);
  int st = pclose(p);
  o.code = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  return o;
}

// A refused file: read_molecule throws Error with exit code 2 naming it (and, when `what` is given, saying
// `what` on one line), and `chokeloops analyze` on it exits 2 with one line.
void expect_refused(const std::string& path, const std::string& what, const fs::path& out) {
  try {
    read_molecule(path);
    ADD_FAILURE() << path << " was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.exit_code, 2) << path;
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    if (!what.empty()) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
      EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
    }
  }
  Outcome o = cli("'" + path + "' -o '" + out.string() + "' --quiet");
  EXPECT_EQ(o.code, 2) << path << ": " << o.err;
  EXPECT_EQ(std::count(o.err.begin(), o.err.end(), '\n'), 1) << o.err;
}
}  // namespace

// Each bad file: Error with exit code 2 naming the file, and the CLI exits 2 with one line.
TEST(MoleculeInput, BadInputExitsTwoWithOneLine) {
  const fs::path dir = test::temp_dir("mol");
  auto write = [&](const std::string& name, const std::string& text) { return test::write_file(dir, name, text); };
  std::string line = "ATOM      1  CA  ALA A   1      11.104   6.134  -6.504  1.00  0.00           C\n";
  std::string good;
  for (int i = 0; i < 20; ++i) good += line;
  // a gzip of a real file, cut in half
  std::string gz = (dir / "cut.pdb.gz").string();
  {
    std::ifstream in(kData + "/molecules/1k4c.pdb");
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    gzFile f = gzopen(gz.c_str(), "wb");
    gzwrite(f, text.data(), unsigned(text.size()));
    gzclose(f);
    std::string bytes;
    {
      std::ifstream b(gz, std::ios::binary);
      bytes.assign((std::istreambuf_iterator<char>(b)), std::istreambuf_iterator<char>());
    }
    std::ofstream(gz, std::ios::binary | std::ios::trunc) << bytes.substr(0, bytes.size() / 2);
  }
  std::string nan_line = "ATOM      2  CB  ALA A   1         nan   6.134  -6.504  1.00  0.00           C\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {write("empty.pdb", ""), "empty"},
      {write("garbled.pdb", "\x01\x02 this is not a structure\nfoo bar\n"), "no atoms"},
      {write("garbled.cif", "data_x\nloop_\n_atom_site.id\n'unterminated\n"), "cif"},
      {gz, "gzip"},
      {write("waters.pdb", "HETATM    1  O   HOH A   1      11.104   6.134  -6.504  1.00  0.00           O\n"), "no atoms left"},
      {write("nan.pdb", good + nan_line), "non-finite"},
  };
  for (auto& [path, what] : cases) expect_refused(path, "", dir / "out");  // `what` names the case only
  fs::remove_all(dir);
}

// Found by fuzzing: gemmi reads integers without an overflow check (undefined behaviour beyond the range of int)
// and expands an assembly's operator range "(1-N)" one name at a time. Such values are refused, with exit code 2
// and one line, before gemmi sees them; ordinary values still read.
TEST(MoleculeInput, FuzzIntegersBeyondIntAndHugeOperatorRangesAreRefused) {
  const fs::path dir = test::temp_dir("mol_fuzz");
  auto write = [&](const std::string& name, const std::string& text) { return test::write_file(dir, name, text); };
  const std::string atoms =
      "loop_\n_atom_site.group_PDB\n_atom_site.id\n_atom_site.type_symbol\n_atom_site.label_atom_id\n"
      "_atom_site.label_alt_id\n_atom_site.label_comp_id\n_atom_site.label_asym_id\n_atom_site.label_seq_id\n"
      "_atom_site.Cartn_x\n_atom_site.Cartn_y\n_atom_site.Cartn_z\n_atom_site.occupancy\n"
      "_atom_site.B_iso_or_equiv\n_atom_site.auth_seq_id\n_atom_site.auth_asym_id\n_atom_site.pdbx_PDB_model_num\n";
  const std::string row1 = "ATOM 1 C CA . GLY A 1 0.000 0.000 0.000 1.00 10.0 1 A 1\n";
  auto assembly = [](const std::string& expr) {
    return "_pdbx_struct_assembly.id 1\n_pdbx_struct_assembly.details author_defined_assembly\n"
           "_pdbx_struct_assembly.method_details ?\n_pdbx_struct_assembly.oligomeric_details monomeric\n"
           "_pdbx_struct_assembly.oligomeric_count 1\n_pdbx_struct_assembly_gen.assembly_id 1\n"
           "_pdbx_struct_assembly_gen.oper_expression " + expr + "\n_pdbx_struct_assembly_gen.asym_id_list A\n";
  };
  const std::string dbref2 = "DBREF1 1ABC A    1    10  UNP                  P12345_HUMAN\n"
                       "DBREF2 1ABC A     P12345                     9999999999  9999999999\n";
  std::ifstream in(std::string(CHOKELOOPS_SOURCE_DIR) + "/fuzz/corpus/cif/regression-cc289392782f", std::ios::binary);
  const std::string corpus((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_FALSE(corpus.empty());
  const std::string pdb_atom = "ATOM      1  CA  ALA A   1      11.104   6.134  -6.504  1.00  0.00           C\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {write("regression.cif", corpus), "beyond 2147483647"},
      {write("serial.cif", "data_x\n" + atoms + "ATOM 99999999999 C CA . GLY A 1 0 0 0 1 10 1 A 1\n"), "beyond 2147483647"},
      {write("seq.cif", "data_x\n" + atoms + "ATOM 1 C CA . GLY A 1 0 0 0 1 10 -4294967296 A 1\n"), "auth_seq_id"},
      {write("range.cif", "data_x\n" + assembly("'(1-2000000000)'") + atoms + row1), "more than 100000 operators"},
      {write("range_int.cif", "data_x\n" + assembly("'(1,3-99999999999)'") + atoms + row1), "beyond 2147483647"},
      {write("dbref.pdb", dbref2 + pdb_atom), "DBREF2"},
  };
  // A 75-column SSBOND (gemmi read its distance, columns 74-78, past the end of the record: heap overflow) and
  // the fuzzed input that found it are read (they are short connection records, not errors).
  {
    std::string ssbond = "SSBOND   1 CYS A    1    CYS A    1";
    ssbond.resize(73, ' ');
    ssbond += "2.";
    ASSERT_EQ(ssbond.size(), 75u);
    EXPECT_EQ(read_molecule(write("ssbond.pdb", ssbond + "\n" + pdb_atom)).atoms.size(), 1u);
    std::ifstream r(std::string(CHOKELOOPS_SOURCE_DIR) + "/fuzz/corpus/pdb/regression-2149ea842f1c", std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(r)), std::istreambuf_iterator<char>());
    ASSERT_FALSE(bytes.empty());
    try {
      read_molecule(write("regression.pdb", bytes));
    } catch (const Error& e) {
      EXPECT_EQ(e.exit_code, 2) << e.what();
    }
  }
  for (auto& [path, what] : cases) expect_refused(path, what, dir / "out");
  // within range: an icosahedral assembly and ordinary numbers are read as before
  Molecule m = read_molecule(write("ok.cif", "data_x\n" + assembly("'(1-60)'") + atoms + row1 +
                                                 "ATOM 2147483647 C CB . GLY A 1 1.5 0 0 1 10 -2147483647 A 1\n"));
  EXPECT_EQ(m.atoms.size(), 2u);
  fs::remove_all(dir);
}

// Found by fuzzing: gemmi begins a record inside a line after a NUL or a byte above 0x7f, so a short SSBOND there
// escaped the padding to 80 columns and gemmi read its distance past the record (heap overflow). Refused with
// exit code 2 and one line; a long ASCII line, which gemmi skips to its end, still reads.
TEST(MoleculeInput, FuzzConnectionRecordBeginningInsideALineIsRefused) {
  const fs::path dir = test::temp_dir("mol_conn");
  auto write = [&](const std::string& name, const std::string& text) { return test::write_file(dir, name, text); };
  const std::string atom = "ATOM      1  CA  ALA A   1      11.104   6.134  -6.504  1.00  0.00           C\n";
  std::ifstream r(std::string(CHOKELOOPS_SOURCE_DIR) + "/fuzz/corpus/pdb/regression-13d3455ba14d", std::ios::binary);
  const std::string found((std::istreambuf_iterator<char>(r)), std::istreambuf_iterator<char>());
  ASSERT_FALSE(found.empty());
  const std::string ssbond = "SSBOND   1 CYS A    1    CYS A    1";
  const std::string remark = "REMARK   1 " + std::string(115, 'x');  // 126 columns: gemmi reads 120
  expect_refused(write("regression.pdb", found), "SSBOND, LINK or CISPEP record", dir / "out");
  expect_refused(write("nul.pdb", atom + "REMARK x" + std::string(1, '\0') + "\n\xff" + ssbond + "\n"),
                 "line 3 holds a NUL or a non-ASCII byte", dir / "out");
  expect_refused(write("long.pdb", atom + remark + "\xff" + ssbond + "\n"), "line 2 holds", dir / "out");
  EXPECT_EQ(read_molecule(write("ascii.pdb", atom + remark + ssbond + "\n")).atoms.size(), 1u);
  fs::remove_all(dir);
}
