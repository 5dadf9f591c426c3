// Biological assemblies (--assembly): KcsA 1k4c is deposited as one subunit and its Fab; REMARK 350 makes the
// tetramer, whose K+ pore runs along the 4-fold axis. mmCIF's _pdbx_struct_assembly on a small file, and the
// refusals (an id the file does not list; a file with no assembly).
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <map>
#include <set>
#include <string>

#include "temp_dir.h"
#include "chokeloops/analyze_molecule.h"

namespace fs = std::filesystem;
using namespace chokeloops;

namespace {

const std::string kKcsA = std::string(CHOKELOOPS_DATA) + "/molecules/1k4c.pdb";
// REMARK 350's operators 2-4 turn chain C about the line x = y = 155.33 Å, parallel to z.
constexpr double kAxisXY = 155.33;

int cli_code(const std::string& args, std::string& err) {
  const std::string cmd = std::string(CHOKELOOPS_CLI) + " analyze " + args + " 2>&1 1>/dev/null";
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) return -1;
  char buf[4096];
  std::size_t n;
  while ((n = fread(buf, 1, sizeof buf, p)) > 0) err.append(buf, n);
  int st = pclose(p);
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

int error_code(const std::function<void()>& f, std::string& what) {
  try {
    f();
  } catch (const Error& e) {
    what = e.what();
    return e.exit_code;
  }
  return 0;
}

}  // namespace

TEST(MoleculeAssembly, KcsATetramerHasFourTimesTheAtomsInNamedCopies) {
  Molecule asu = read_molecule(kKcsA);
  bool hinted = false;
  for (auto& w : asu.warnings) hinted |= w.find("--assembly 1") != std::string::npos;
  EXPECT_TRUE(hinted) << "the asymmetric unit of an oligomer, read as stored, should say how to build it";

  MoleculeReadOptions o;
  o.assembly = "1";
  Molecule bio = read_molecule(kKcsA, o);
  EXPECT_EQ(bio.assembly, "1");
  EXPECT_EQ(bio.assembly_operators, 4);
  EXPECT_EQ(bio.atoms.size(), 4 * asu.atoms.size());
  std::map<std::string, int> per_chain;
  for (auto& a : bio.atoms) per_chain[a.chain] += 1;
  std::map<std::string, int> asu_chain;
  for (auto& a : asu.atoms) asu_chain[a.chain] += 1;
  ASSERT_EQ(per_chain.size(), 12u);  // A, B, C, four copies each, with distinct names
  for (auto& [name, n] : asu_chain)
    for (int k = 1; k <= 4; ++k) EXPECT_EQ(per_chain[name + std::to_string(k)], n) << name << k;

  // --chains names the file's chains: the four copies of the channel subunit, C1..C4
  o.chains = {"C"};
  Molecule channel = read_molecule(kKcsA, o);
  EXPECT_EQ(channel.atoms.size(), 4u * std::size_t(asu_chain["C"]));
  // the copies are turned by 90 degrees about the 4-fold axis: their centroids are equally far from it
  std::map<std::string, std::array<double, 4>> centroid;
  for (auto& a : channel.atoms) {
    auto& c = centroid[a.chain];
    for (int i = 0; i < 3; ++i) c[std::size_t(i)] += a.pos[std::size_t(i)];
    c[3] += 1;
  }
  ASSERT_EQ(centroid.size(), 4u);
  std::vector<double> dist;
  for (auto& [name, c] : centroid) dist.push_back(std::hypot(c[0] / c[3] - kAxisXY, c[1] / c[3] - kAxisXY));
  for (double d : dist) EXPECT_NEAR(d, dist[0], 1e-6);

  // atoms on the axis (the K+ of the filter, a water below the gate) are copied onto themselves: gemmi merges
  // them, so with every residue kept the assembly has 4x the other atoms and each of these once
  MoleculeReadOptions all;
  all.ignore_set = true;
  Molecule asu_all = read_molecule(kKcsA, all);
  all.assembly = "1";
  Molecule bio_all = read_molecule(kKcsA, all);
  std::size_t on_axis = 0;
  int k_asu = 0, k_bio = 0;
  for (auto& a : asu_all.atoms) {
    on_axis += std::hypot(a.pos[0] - kAxisXY, a.pos[1] - kAxisXY) < 0.1;
    k_asu += a.resname == "K";
  }
  for (auto& a : bio_all.atoms) k_bio += a.resname == "K";
  EXPECT_EQ(k_asu, 7);
  EXPECT_EQ(k_bio, 7);
  EXPECT_EQ(on_axis, 8u);
  EXPECT_EQ(bio_all.atoms.size(), 4 * (asu_all.atoms.size() - on_axis) + on_axis);
}

TEST(MoleculeAssembly, UnknownIdOrNoAssemblyIsBadInputNamingTheIds) {
  std::string what;
  MoleculeReadOptions o;
  o.assembly = "7";
  EXPECT_EQ(error_code([&] { read_molecule(kKcsA, o); }, what), 2);
  EXPECT_NE(what.find(kKcsA), std::string::npos) << what;
  EXPECT_NE(what.find("'7'"), std::string::npos) << what;
  EXPECT_NE(what.find("(it lists: 1)"), std::string::npos) << what;
  EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  o.assembly = "1";
  const std::string gramicidin = std::string(CHOKELOOPS_DATA) + "/molecules/1grm_single_hole2.pdb";
  EXPECT_EQ(error_code([&] { read_molecule(gramicidin, o); }, what), 2);
  EXPECT_NE(what.find("lists no biological assembly"), std::string::npos) << what;
  o.assembly = "none";
  EXPECT_EQ(read_molecule(gramicidin, o).assembly, "");

  const fs::path dir = test::temp_dir("assembly_cli");
  std::string err;
  EXPECT_EQ(cli_code("'" + kKcsA + "' --assembly 2 -o '" + (dir / "out").string() + "' --quiet", err), 2);
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  EXPECT_NE(err.find("1k4c.pdb"), std::string::npos) << err;
  EXPECT_NE(err.find("(it lists: 1)"), std::string::npos) << err;
  fs::remove_all(dir);
}

// mmCIF assemblies name subchains (label_asym_id) and operators by id: a two-atom residue and a 2-fold turn.
TEST(MoleculeAssembly, MmcifStructAssemblyIsBuilt) {
  const fs::path dir = test::temp_dir("assembly_cif");
  const std::string cif = test::write_file(dir, "pair.cif", R"(data_PAIR
loop_
_atom_site.group_PDB
_atom_site.id
_atom_site.type_symbol
_atom_site.label_atom_id
_atom_site.label_alt_id
_atom_site.label_comp_id
_atom_site.label_asym_id
_atom_site.label_entity_id
_atom_site.label_seq_id
_atom_site.pdbx_PDB_ins_code
_atom_site.Cartn_x
_atom_site.Cartn_y
_atom_site.Cartn_z
_atom_site.occupancy
_atom_site.B_iso_or_equiv
_atom_site.auth_seq_id
_atom_site.auth_asym_id
_atom_site.pdbx_PDB_model_num
ATOM 1 C CA . GLY A 1 1 ? 5.0 0.0 0.0 1.0 10.0 1 P 1
ATOM 2 O O  . GLY A 1 1 ? 6.5 0.0 0.0 1.0 10.0 1 P 1
#
_pdbx_struct_assembly.id 1
_pdbx_struct_assembly.details author_defined_assembly
_pdbx_struct_assembly.method_details ?
_pdbx_struct_assembly.oligomeric_details dimeric
_pdbx_struct_assembly.oligomeric_count 2
#
_pdbx_struct_assembly_gen.assembly_id 1
_pdbx_struct_assembly_gen.oper_expression 1,2
_pdbx_struct_assembly_gen.asym_id_list A
#
loop_
_pdbx_struct_oper_list.id
_pdbx_struct_oper_list.type
_pdbx_struct_oper_list.matrix[1][1]
_pdbx_struct_oper_list.matrix[1][2]
_pdbx_struct_oper_list.matrix[1][3]
_pdbx_struct_oper_list.vector[1]
_pdbx_struct_oper_list.matrix[2][1]
_pdbx_struct_oper_list.matrix[2][2]
_pdbx_struct_oper_list.matrix[2][3]
_pdbx_struct_oper_list.vector[2]
_pdbx_struct_oper_list.matrix[3][1]
_pdbx_struct_oper_list.matrix[3][2]
_pdbx_struct_oper_list.matrix[3][3]
_pdbx_struct_oper_list.vector[3]
1 'identity operation' 1 0 0 0 0 1 0 0 0 0 1 0
2 'point symmetry operation' -1 0 0 0 0 -1 0 0 0 0 1 0
#
)");
  MoleculeReadOptions o;
  EXPECT_EQ(read_molecule(cif, o).atoms.size(), 2u);
  o.assembly = "1";
  Molecule m = read_molecule(cif, o);
  ASSERT_EQ(m.atoms.size(), 4u);
  std::set<std::string> chains;
  double xs = 0;
  for (auto& a : m.atoms) chains.insert(a.chain), xs += a.pos[0];
  EXPECT_EQ(chains, (std::set<std::string>{"P1", "P2"}));
  EXPECT_NEAR(xs, 0, 1e-9);  // the copy is turned about z
  std::string what;
  o.assembly = "3";
  EXPECT_EQ(error_code([&] { read_molecule(cif, o); }, what), 2);
  EXPECT_NE(what.find("(it lists: 1)"), std::string::npos) << what;
  fs::remove_all(dir);
}

// The tetramer of the channel subunit (four copies of chain C) end to end: its K+ pore runs along the 4-fold
// axis and is narrowest in the selectivity filter (TVGYG, 75-79), at the Thr75 carbonyls of all four copies
// (0.747 A at 0.5 A voxels; narrower than CAVER's 0.9 A probe, so --min-radius 0.7 traces it).
TEST(MoleculeAssembly, KcsAPoreRunsAlongTheFourFoldAxisThroughTheFilter) {
  AnalyzeOptions ao;
  ao.levelset.voxel_size = 0.5;
  ao.chokes.handles = false;
  MoleculeOptions mo;
  mo.read.assembly = "1";
  mo.read.chains = {"C"};
  mo.channels.trace_unsectioned = false;
  mo.channels.min_radius = 0.7;
  MoleculeAnalysis m = analyze_molecule(kKcsA, ao, mo);
  MoleculeReadOptions c_only;
  c_only.chains = {"C"};
  EXPECT_EQ(m.molecule.atoms.size(), 4 * read_molecule(kKcsA, c_only).atoms.size());

  const Channel* pore = nullptr;
  for (auto& c : m.channels)
    if (c.traced && std::hypot(c.bottleneck[0] - kAxisXY, c.bottleneck[1] - kAxisXY) < 0.5) pore = &c;
  ASSERT_NE(pore, nullptr) << "no traced tunnel with its bottleneck on the 4-fold axis";
  EXPECT_GT(std::abs(pore->axis[2]), 0.95);
  EXPECT_NEAR(pore->bottleneck_radius, 0.75, 0.1);
  EXPECT_TRUE(pore->open[0] && pore->open[1]);
  EXPECT_GT(pore->length, 30.0);
  std::set<std::string> filter;
  for (auto& l : pore->bottleneck_lining) {
    const MolAtom& a = m.molecule.atoms[std::size_t(l.atom)];
    if (a.resseq >= 75 && a.resseq <= 79) filter.insert(a.chain);
  }
  EXPECT_EQ(filter, (std::set<std::string>{"C1", "C2", "C3", "C4"}));
  // through the filter the path stays on the axis
  int on_axis = 0;
  for (auto& p : pore->profile)
    if (std::abs(p.s) <= 8) {
      EXPECT_LT(std::hypot(p.p[0] - kAxisXY, p.p[1] - kAxisXY), 1.0) << "s " << p.s;
      ++on_axis;
    }
  EXPECT_GT(on_axis, 8);
  const Loop& loop = m.result.loops[std::size_t(pore->loop)];
  EXPECT_TRUE(loop.found || !loop.note.empty());
}
