// Molecule outputs beside the usual report: what HOLE/CAVER users load (CSV tables, .sph-style PDB, PyMOL).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "chokeloops/analyze_molecule.h"

namespace chokeloops {

namespace {

std::ofstream open_out(const std::string& path) {
  std::ofstream out(path);
  if (!out) throw Error("cannot write '" + path + "'");
  return out;
}

std::string residue_key(const MolAtom& a) {
  std::string s = a.chain + ":" + a.resname + ":" + std::to_string(a.resseq);
  if (a.icode != ' ' && a.icode) s += a.icode;
  return s;
}

// Residues in order of their closest atom.
std::string residues(const Molecule& mol, const std::vector<LiningAtom>& lining) {
  std::set<std::string> seen;
  std::string out;
  for (auto& l : lining) {
    std::string k = residue_key(mol.atoms[std::size_t(l.atom)]);
    if (!seen.insert(k).second) continue;
    out += (out.empty() ? "" : ";") + k;
  }
  return out;
}

}  // namespace

void write_molecule_report(const MoleculeAnalysis& m, const MoleculeOptions& options, const std::string& outdir) {
  const Molecule& mol = m.molecule;
  const auto& loops = m.result.loops;
  {
    auto out = open_out(outdir + "/tunnels.csv");
    out << "id,kind,bottleneck_radius,x,y,z,length,lining_residues\n";
    char buf[256];
    for (auto& c : m.channels) {
      std::snprintf(buf, sizeof buf, "%d,%s,%.4f,%.4f,%.4f,%.4f,%.3f,", c.loop, to_string(loops[std::size_t(c.loop)].choke.kind),
                    c.bottleneck_radius, c.bottleneck[0], c.bottleneck[1], c.bottleneck[2], c.length);
      out << buf << residues(mol, c.bottleneck_lining) << "\n";
    }
  }
  {
    auto out = open_out(outdir + "/profiles.csv");
    out << "id,s,x,y,z,radius\n";
    char buf[200];
    for (auto& c : m.channels)
      for (auto& p : c.profile) {
        std::snprintf(buf, sizeof buf, "%d,%.3f,%.4f,%.4f,%.4f,%.4f\n", c.loop, p.s, p.p[0], p.p[1], p.p[2], p.radius);
        out << buf;
      }
  }
  {
    auto out = open_out(outdir + "/lining.csv");
    out << "id,chain,resname,resseq,atom,distance\n";
    char buf[200];
    for (auto& c : m.channels)
      for (auto& l : c.lining) {
        const MolAtom& a = mol.atoms[std::size_t(l.atom)];
        std::snprintf(buf, sizeof buf, "%d,%s,%s,%d,%s,%.4f\n", c.loop, a.chain.c_str(), a.resname.c_str(), a.resseq,
                      a.name.c_str(), l.distance);
        out << buf;
      }
  }
  {
    // HOLE's .sph convention: one pseudo-atom per profile point, radius in the B-factor column
    auto out = open_out(outdir + "/channels.pdb");
    out << "REMARK   chokeloops tunnel paths: residue number = tunnel id, B-factor = radius (A)\n";
    int serial = 1;
    char buf[128];
    for (auto& c : m.channels)
      for (auto& p : c.profile) {
        std::snprintf(buf, sizeof buf, "ATOM  %5d  QSS SPH S%4d    %8.3f%8.3f%8.3f%6.2f%6.2f\n", serial % 100000,
                      c.loop % 10000, p.p[0], p.p[1], p.p[2], 1.0, std::min(p.radius, 999.99));
        out << buf;
        ++serial;
      }
    out << "END\n";
  }
  {
    auto out = open_out(outdir + "/view.pml");
    std::string structure = std::filesystem::absolute(mol.path).string();
    out << "# PyMOL: pymol " << outdir << "/view.pml\n";
    // PyMOL builds assemblies of mmCIF files only; for a PDB file the paths overlay its first copy
    if (!mol.assembly.empty()) out << "set assembly, " << mol.assembly << "\n";
    out << "load " << structure << ", structure\n"
        << "hide everything, structure\nshow sticks, structure\nshow surface, structure\nset transparency, 0.6\n"
        << "load " << std::filesystem::absolute(outdir + "/channels.pdb").string() << ", paths\n"
        << "alter paths, vdw=b\nrebuild\nshow spheres, paths\nspectrum b, red_yellow_blue, paths\n"
        << "python\nfrom pymol.cgo import BEGIN, END, LINE_STRIP, VERTEX, COLOR, LINEWIDTH\nfrom pymol import cmd\n";
    char buf[160];
    for (std::size_t i = 0; i < loops.size(); ++i) {
      const Loop& l = loops[i];
      if (!l.found || l.points.empty()) continue;
      const bool tunnel = l.choke.side == Side::Tunnel;
      out << "cmd.load_cgo([LINEWIDTH, 3.0, BEGIN, LINE_STRIP, COLOR, " << (tunnel ? "0.2, 0.4, 1.0" : "1.0, 0.2, 0.2");
      for (std::size_t k = 0; k <= l.points.size(); ++k) {
        const auto& p = l.points[k % l.points.size()];
        std::snprintf(buf, sizeof buf, ", VERTEX, %.3f, %.3f, %.3f", p[0], p[1], p[2]);
        out << buf;
      }
      out << ", END], '" << (tunnel ? "tunnel_" : "handle_") << i << "')\n";
    }
    out << "python end\ngroup loops, tunnel_* handle_*\nzoom structure\n";
  }
  // loops.json: the contract's fields stay; each tunnel loop gains its channel, the file a "molecule" section
  const std::string jpath = outdir + "/loops.json";
  nlohmann::json j;
  {
    std::ifstream in(jpath);
    if (!in) throw Error("cannot read back '" + jpath + "'");
    in >> j;
  }
  j["units"] = "angstrom";
  j["molecule"] = {{"atoms", mol.atoms.size()},
                   {"ignored_atoms", mol.ignored_atoms},
                   {"model", mol.model},
                   {"assembly", mol.assembly.empty() ? "none" : mol.assembly},
                   {"assembly_operators", mol.assembly_operators},
                   {"surface", to_string(options.field.surface)},
                   {"probe", options.field.probe},
                   {"radii", options.read.radii == RadiusSet::Amber ? "amber" : "bondi"}};
  for (auto& c : m.channels) {
    nlohmann::json lin = nlohmann::json::array();
    for (auto& l : c.bottleneck_lining) {
      const MolAtom& a = mol.atoms[std::size_t(l.atom)];
      lin.push_back({{"chain", a.chain}, {"resname", a.resname}, {"resseq", a.resseq}, {"atom", a.name}, {"distance", l.distance}});
    }
    // the radius profile for plots (view.html): arc length from the bottleneck and radius, as profiles.csv
    nlohmann::json s = nlohmann::json::array(), radius = nlohmann::json::array();
    for (auto& p : c.profile) s.push_back(std::round(p.s * 1000) / 1000), radius.push_back(std::round(p.radius * 1e4) / 1e4);
    j["loops"][std::size_t(c.loop)]["channel"] = {
        {"bottleneck_radius", c.bottleneck_radius}, {"grid_radius", c.grid_radius}, {"refined", c.refined},
        {"bottleneck", {c.bottleneck[0], c.bottleneck[1], c.bottleneck[2]}}, {"axis", {c.axis[0], c.axis[1], c.axis[2]}},
        {"length", c.length}, {"open_ends", int(c.open[0]) + int(c.open[1])}, {"section_length", c.section_length},
        {"bottleneck_lining", lin}, {"profile", {{"s", s}, {"radius", radius}}}, {"note", c.note}};
  }
  std::ofstream out(jpath);
  out << j.dump(1) << "\n";
  if (!out) throw Error("cannot write '" + jpath + "'");
}

}  // namespace chokeloops
