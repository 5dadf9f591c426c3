#pragma once
// Molecule input (PDB / mmCIF, optionally gzipped) read with gemmi: atoms with their van der Waals radii,
// in Å, in the structure's frame (DESIGN §6 "Molecules").
#include <array>
#include <string>
#include <vector>

namespace chokeloops {

enum class RadiusSet { Bondi, Amber };

struct MoleculeReadOptions {
  int model = 1;                     // model number (MODEL record / pdbx_PDB_model_num), 1-based
  std::vector<std::string> ignore;   // residue names dropped; default_ignored_residues() unless set
  bool ignore_set = false;           // true: `ignore` is the list (possibly empty), else the default
  std::vector<std::string> chains;   // keep only these chains (empty: all); with an assembly, the file's
                                     // chains, every copy of them kept
  // Biological assembly to build from the file's own records (REMARK 350 BIOMT / _pdbx_struct_assembly),
  // by its id ("1"): a deposited crystal structure is often the asymmetric unit, and a pore between subunits
  // exists only in the assembly. Empty or "none": the coordinates as stored, as HOLE and CAVER read them.
  std::string assembly;
  RadiusSet radii = RadiusSet::Bondi;
};

struct MolAtom {
  std::array<double, 3> pos{0, 0, 0};
  double radius = 0;     // van der Waals radius of the chosen set, Å
  std::string element;   // "C", "FE", ...
  std::string name;      // atom name, e.g. "CA"
  std::string resname;   // e.g. "TRP"
  std::string chain;
  int resseq = 0;
  char icode = ' ';
};

struct Molecule {
  std::string path;
  std::vector<MolAtom> atoms;
  std::vector<std::string> warnings;  // one line each
  int model = 1;
  int ignored_atoms = 0;              // dropped by the residue list, chains or altlocs
  std::string assembly;               // the assembly built ("" when as stored)
  int assembly_operators = 0;         // operators it applied (copies of its chains)
};

// Waters and the common monatomic ions.
const std::vector<std::string>& default_ignored_residues();

// .pdb .ent .cif .mmcif, each optionally .gz (case-insensitive).
bool is_molecule_path(const std::string& path);

// Radius of an element (upper case, e.g. "C", "SE") in a set; *known = false when the set does not have it
// (then Bondi's value if Bondi has it, else 2.0 Å).
double element_radius(const std::string& element, RadiusSet set, bool* known = nullptr);

// Reads one model: alternate locations keep the highest occupancy per atom, ignored residues and other
// chains are dropped, hydrogens are kept. Throws chokeloops::Error (exit code 2) with one line naming the
// file for: missing, empty, garbled or truncated (gz) files, no such model, no atoms left after the
// filters, non-finite coordinates, an assembly id the file does not list (the line names the ids it has).
// Copies of a chain in an assembly are named by gemmi's AddNumber rule (C -> C1, C2, ...); atoms that
// copies put on the same spot (an ion on a symmetry axis) are merged, as gemmi does.
Molecule read_molecule(const std::string& path, const MoleculeReadOptions& options = {});

}  // namespace chokeloops
