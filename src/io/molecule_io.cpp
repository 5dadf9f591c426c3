// Molecule input: gemmi parses, this file only chooses what to keep and which radius each atom gets.
#include "chokeloops/io/molecule_io.h"

#include <zlib.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <iterator>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include <gemmi/assembly.hpp>
#include <gemmi/cif.hpp>
#include <gemmi/mmcif.hpp>
#include <gemmi/pdb.hpp>

#include "chokeloops/grid.h"

namespace chokeloops {

namespace {

std::string lower(std::string s) {
  for (auto& c : s) c = char(std::tolower((unsigned char)c));
  return s;
}
bool ends_with(const std::string& s, const std::string& t) {
  return s.size() >= t.size() && s.compare(s.size() - t.size(), t.size(), t) == 0;
}
std::string strip_gz(const std::string& path) {
  std::string l = lower(path);
  return ends_with(l, ".gz") ? l.substr(0, l.size() - 3) : l;
}
bool is_cif(const std::string& path) {
  std::string b = strip_gz(path);
  return ends_with(b, ".cif") || ends_with(b, ".mmcif");
}

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw Error(path + ": " + what, 2);
}

// gemmi reads a truncated .gz without complaint; zlib's close says whether the stream ended properly.
std::string read_all(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) fail(path, "no such file");
  if (std::filesystem::is_directory(path, ec)) fail(path, "is a directory, not a structure file");
  std::string text;
  if (ends_with(lower(path), ".gz")) {
    gzFile f = gzopen(path.c_str(), "rb");
    if (!f) fail(path, "cannot open");
    char buf[1 << 16];
    int n;
    while ((n = gzread(f, buf, sizeof buf)) > 0) text.append(buf, std::size_t(n));
    int err = 0;
    std::string msg = n < 0 ? gzerror(f, &err) : "";
    int close = gzclose_r(f);
    if (n < 0) fail(path, "corrupt gzip data (" + msg + ")");
    if (close != Z_OK) fail(path, "truncated or corrupt gzip file");
  } else {
    std::ifstream in(path, std::ios::binary);
    if (!in) fail(path, "cannot open");
    std::ostringstream s;
    s << in.rdbuf();
    text = s.str();
  }
  if (text.find_first_not_of(" \t\r\n") == std::string::npos) fail(path, "empty file");
  return text;
}

// HOLE's example files carry a line number in columns 73-80, so columns 77-80 hold digits, not an element
// and a charge, and gemmi refuses the "charge". Those columns are blanked, gemmi then takes the element from
// the atom name, and the user is told.
int blank_digit_element_columns(std::string& text) {
  int count = 0;
  std::size_t pos = 0;
  while (pos < text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    if (end - pos > 77 && (text.compare(pos, 4, "ATOM") == 0 || text.compare(pos, 6, "HETATM") == 0)) {
      char a = text[pos + 76], b = text[pos + 77];
      if (!std::isalpha((unsigned char)a) && !std::isalpha((unsigned char)b) &&
          (std::isdigit((unsigned char)a) || std::isdigit((unsigned char)b))) {
        for (std::size_t c = pos + 76; c < end && c < pos + 80; ++c)
          if (text[c] != '\r') text[c] = ' ';
        ++count;
      }
    }
    pos = end + 1;
  }
  return count;
}

// ---- what gemmi trusts (found by fuzzing) ----
// gemmi's integer parsing (string_to_int, no_sign_atoi) does not check for overflow: a number beyond the range of
// int is undefined behaviour there, and the operator ranges of an assembly ("(1-60)") are expanded one name at a
// time, so "(1-2000000000)" would fill the memory. The items gemmi reads that way are checked here first.
constexpr long long kMaxOperators = 100000;  // operator names one assembly generator may expand to

bool is_space_char(char c) { return c == ' ' || (c >= 9 && c <= 13); }

// The magnitude of the integer gemmi reads at the start of v (spaces, a sign, digits; at most `length`
// characters when length > 0): -1 when it does not fit in an int, 0 when there is none.
long long leading_int(const char* v, std::size_t n, bool sign) {
  std::size_t i = 0;
  while (i < n && is_space_char(v[i])) ++i;
  if (sign && i < n && (v[i] == '-' || v[i] == '+')) ++i;
  long long x = 0;
  for (; i < n && std::isdigit(static_cast<unsigned char>(v[i])); ++i) {
    x = x * 10 + (v[i] - '0');
    if (x > 2147483647LL) return -1;
  }
  return x;
}

std::string shown(std::string v) {
  if (v.size() > 40) v = v.substr(0, 37) + "...";
  for (auto& c : v)
    if (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126) c = '?';
  return v;
}

// mmCIF items (lower case) that make_structure converts with string_to_int / no_sign_atoi, besides every *seq_id.
bool gemmi_int_item(const std::string& tag) {
  static const std::set<std::string> items = {
      "_atom_site.id", "_atom_site.pdbx_formal_charge", "_atom_site.pdbx_tls_group_id",
      "_struct_conf.pdbx_pdb_helix_class", "_struct_conf.pdbx_pdb_helix_length",
      "_pdbx_struct_assembly.oligomeric_count", "_pdbx_sifts_xref_db.unp_num", "_refine.ls_number_reflns_obs",
      "_exptl.crystals_number", "_reflns.number_obs", "_software.pdbx_ordinal", "_entity_poly_seq.num",
      "_struct_ref_seq.seq_align_beg", "_struct_ref_seq.seq_align_end", "_struct_ref_seq.db_align_beg",
      "_struct_ref_seq.db_align_end", "_struct_ref_seq.pdbx_auth_seq_align_beg",
      "_struct_ref_seq.pdbx_auth_seq_align_end"};
  return ends_with(tag, "seq_id") || items.count(tag) > 0;
}

// How many operator names gemmi's parse_operation_expr makes of an oper_expression, counted the way it
// parses (without making them); -1 when a number in it does not fit in an int.
long long operator_count(const std::string& expr) {
  std::size_t start = 0, close_br = std::string::npos;
  if (!expr.empty() && expr[0] == '(') {
    start = 1;
    close_br = expr.find(')');
  }
  long long total = 0;
  for (;;) {
    const std::size_t sep = std::min(expr.find(',', start), close_br);
    const std::size_t minus = expr.find('-', start);
    if (minus < sep) {
      const long long lo = leading_int(expr.c_str() + start, expr.size() - start, false);
      const long long hi = leading_int(expr.c_str() + minus + 1, expr.size() - minus - 1, false);
      if (lo < 0 || hi < 0) return -1;
      if (hi >= lo) total += hi - lo + 1;
    } else {
      total += 1;
    }
    if (total > kMaxOperators || sep == close_br) break;
    start = sep + 1;
  }
  return total;
}

void check_cif_for_gemmi(const gemmi::cif::Document& doc, const std::string& path) {
  auto check = [&](const std::string& tag_any_case, const std::string& value) {
    const std::string tag = lower(tag_any_case);
    if (gemmi_int_item(tag) && leading_int(value.c_str(), value.size(), true) < 0)
      fail(path, "mmCIF value '" + shown(value) + "' of " + tag_any_case +
                     " is an integer beyond 2147483647, which this reader cannot hold");
    if (tag == "_pdbx_struct_assembly_gen.oper_expression") {
      const long long n = operator_count(gemmi::cif::as_string(value));
      if (n < 0 || n > kMaxOperators)
        fail(path, "mmCIF assembly operator expression '" + shown(value) + "' names " +
                       (n < 0 ? std::string("operators beyond 2147483647") :
                                "more than " + std::to_string(kMaxOperators) + " operators"));
    }
  };
  for (const gemmi::cif::Block& block : doc.blocks)
    for (const gemmi::cif::Item& item : block.items) {
      if (item.type == gemmi::cif::ItemType::Pair) {
        check(item.pair[0], item.pair[1]);
      } else if (item.type == gemmi::cif::ItemType::Loop) {
        const std::size_t w = item.loop.tags.size();
        for (std::size_t c = 0; c < w; ++c)
          for (std::size_t i = c; i < item.loop.values.size(); i += w) check(item.loop.tags[c], item.loop.values[i]);
      }
    }
}

// PDB: the only integer fields gemmi reads wider than 9 digits are the two 10-column sequence numbers of DBREF2.
void check_pdb_for_gemmi(const std::string& text, const std::string& path) {
  std::size_t pos = 0, lineno = 0;
  while (pos < text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    ++lineno;
    const std::size_t len = end - pos;
    if (len > 45 && text[pos + 5] == '2' && lower(text.substr(pos, 4)) == "dbre")
      for (std::size_t col : {std::size_t(45), std::size_t(57)})
        if (col < len && leading_int(text.c_str() + pos + col, std::min<std::size_t>(10, len - col), true) < 0)
          fail(path, "line " + std::to_string(lineno) + ": DBREF2 sequence number '" +
                         shown(text.substr(pos + col, std::min<std::size_t>(10, len - col))) +
                         "' is beyond 2147483647");
    pos = end + 1;
  }
}

// gemmi keeps SSBOND, LINK and CISPEP records as strings and reads their fixed columns later without checking
// the string's length (SSBOND's distance, columns 74-78, is read when the line is longer than 73: a heap
// overflow on a 75-column line; found by fuzzing). Such records are padded with blanks to the 80 columns of the
// format, which is what missing columns mean, and a NUL inside one (which would end gemmi's copy) becomes a blank.
std::uint32_t id4(const char* s) {  // gemmi's ialpha4_id (the first four characters, case folded), same bits
  auto u = [&](int i) { return std::uint32_t(int(s[i])); };
  return (u(0) << 24 | u(1) << 16 | u(2) << 8 | u(3)) & ~0x20202020u;
}
const std::uint32_t kConn[] = {id4("SSBO"), id4("LINK"), id4("CISP")};

int pad_connection_records(std::string& text) {
  std::string out;
  int padded = 0;
  std::size_t pos = 0;
  while (pos < text.size()) {
    std::size_t end = text.find('\n', pos);
    const bool newline = end != std::string::npos;
    if (!newline) end = text.size();
    std::string line = text.substr(pos, end - pos);
    if (line.size() >= 4 && std::find(std::begin(kConn), std::end(kConn), id4(line.c_str())) != std::end(kConn)) {
      const bool cr = !line.empty() && line.back() == '\r';
      if (cr) line.pop_back();
      std::replace(line.begin(), line.end(), '\0', ' ');
      if (line.size() < 80) line.resize(80, ' ');
      if (cr) line.push_back('\r');
      ++padded;
    }
    out += line;
    if (newline) out += '\n';
    pos = end + 1;
  }
  if (padded) text.swap(out);
  return padded;
}

// gemmi does not split the text only at '\n': copy_line_from_stream takes at most 120 characters, ends a record at
// a NUL and then skips the rest of the line, but that skip also stops at a NUL or at a byte above 0x7f (a negative
// char), and gemmi's next record begins there, inside the line. A connection record beginning inside a line was not
// padded above (found by fuzzing: "SSBO" after a NUL and a 0xff, then a heap overflow reading its distance), so a
// file where gemmi would see one is refused; a PDB file has no NULs, and no record begins inside a line.
void check_pdb_record_starts(const std::string& text, const std::string& path) {
  const std::size_t n = text.size();
  std::size_t cur = 0;
  while (cur < n) {
    const std::size_t start = cur, take = std::min<std::size_t>(120, n - cur);
    const void* nl = std::memchr(text.data() + cur, '\n', take);
    cur += nl ? std::size_t(static_cast<const char*>(nl) - (text.data() + cur)) + 1 : take;
    const std::size_t len = strnlen(text.data() + start, cur - start);  // gemmi's strlen
    if (len == 0) break;                                                  // gemmi stops at an empty record
    if (start > 0 && text[start - 1] != '\n' && len >= 4 &&
        std::find(std::begin(kConn), std::end(kConn), id4(text.data() + start)) != std::end(kConn))
      fail(path, "line " + std::to_string(std::count(text.begin(), text.begin() + long(start), '\n') + 1) +
                     " holds a NUL or a non-ASCII byte followed by a SSBOND, LINK or CISPEP record; not a PDB text file");
    if (text[start + len - 1] != '\n')
      while (cur < n) {
        const signed char c = static_cast<signed char>(text[cur++]);
        if (c <= 0 || c == '\n') break;
      }
  }
}

std::string assembly_ids(const gemmi::Structure& st) {
  std::string ids;
  for (const gemmi::Assembly& a : st.assemblies) ids += (ids.empty() ? "" : ", ") + a.name;
  return ids;
}

int operator_total(const gemmi::Assembly& a) {
  int n = 0;
  for (const gemmi::Assembly::Gen& g : a.generators) n += int(g.operators.size());
  return n;
}

// Builds the assembly with gemmi (its operators, chain naming and merging of copies that coincide, e.g. ions
// on a symmetry axis). --chains names the file's chains and is applied first, so every copy of them stays.
void build_assembly(gemmi::Structure& st, const MoleculeReadOptions& options, const std::string& path, Molecule& mol) {
  const gemmi::Assembly* a = st.find_assembly(options.assembly);
  if (!a) {
    if (st.assemblies.empty())
      fail(path, "--assembly " + options.assembly +
                     ": the file lists no biological assembly (no REMARK 350 BIOMT or _pdbx_struct_assembly)");
    fail(path, "has no biological assembly '" + options.assembly + "' (it lists: " + assembly_ids(st) + ")");
  }
  mol.assembly = a->name;
  mol.assembly_operators = operator_total(*a);
  if (!options.chains.empty()) {
    const std::set<std::string> keep(options.chains.begin(), options.chains.end());
    for (gemmi::Model& model : st.models)
      for (std::size_t c = model.chains.size(); c-- > 0;)
        if (!keep.count(model.chains[c].name)) {
          for (const gemmi::Residue& res : model.chains[c].residues) mol.ignored_atoms += int(res.atoms.size());
          model.chains.erase(model.chains.begin() + long(c));
        }
  }
  gemmi::transform_to_assembly(st, a->name, gemmi::HowToNameCopiedChain::AddNumber, nullptr);
}

// A file whose first assembly moves atoms (a crystal's asymmetric unit of an oligomer) analysed as stored
// lacks the pores between its copies; the user is told how to build it.
std::string assembly_hint(const gemmi::Structure& st) {
  if (st.assemblies.empty()) return {};
  const gemmi::Assembly& a = st.assemblies.front();
  bool moves = false;
  for (const gemmi::Assembly::Gen& g : a.generators)
    for (const gemmi::Assembly::Operator& op : g.operators) moves = moves || !op.transform.is_identity();
  if (!moves) return {};
  return "analysed as stored; the file's biological assembly " + a.name + " applies " +
         std::to_string(operator_total(a)) + " operators to its chains (--assembly " + a.name +
         " builds it; pores between copies exist only there)";
}

struct Radius {
  const char* element;
  double r;
};
// Bondi, J. Phys. Chem. 68, 441 (1964), Table I.
const Radius kBondi[] = {{"H", 1.20},  {"HE", 1.40}, {"LI", 1.82}, {"C", 1.70},  {"N", 1.55},  {"O", 1.52},
                         {"F", 1.47},  {"NE", 1.54}, {"NA", 2.27}, {"MG", 1.73}, {"SI", 2.10}, {"P", 1.80},
                         {"S", 1.80},  {"CL", 1.75}, {"AR", 1.88}, {"K", 2.75},  {"NI", 1.63}, {"CU", 1.40},
                         {"ZN", 1.39}, {"GA", 1.87}, {"AS", 1.85}, {"SE", 1.90}, {"BR", 1.85}, {"KR", 2.02},
                         {"PD", 1.63}, {"AG", 1.72}, {"CD", 1.58}, {"IN", 1.93}, {"SN", 2.17}, {"TE", 2.06},
                         {"I", 1.98},  {"XE", 2.16}, {"PT", 1.72}, {"AU", 1.66}, {"HG", 1.55}, {"TL", 1.96},
                         {"PB", 2.02}, {"U", 1.86}};
// HOLE's simple.rad (AMBER united-atom radii as HOLE distributes them).
const Radius kAmber[] = {{"C", 1.85}, {"O", 1.65}, {"N", 1.75}, {"S", 2.00}, {"H", 1.00}, {"P", 2.10}};
constexpr double kFallbackRadius = 2.0;

template <std::size_t N>
const Radius* find(const Radius (&table)[N], const std::string& e) {
  for (auto& r : table)
    if (e == r.element) return &r;
  return nullptr;
}

}  // namespace

const std::vector<std::string>& default_ignored_residues() {
  static const std::vector<std::string> v = {"HOH", "WAT", "H2O", "DOD", "SOL", "TIP", "TIP3", "SPC",
                                             "NA",  "K",   "CL",  "CA",  "MG",  "ZN",  "MN",   "LI",
                                             "RB",  "CS",  "BR",  "IOD", "F",   "SR",  "BA",   "CD"};
  return v;
}

bool is_molecule_path(const std::string& path) {
  std::string b = strip_gz(path);
  for (const char* e : {".pdb", ".ent", ".cif", ".mmcif"})
    if (ends_with(b, e)) return true;
  return false;
}

double element_radius(const std::string& element, RadiusSet set, bool* known) {
  if (set == RadiusSet::Amber)
    if (const Radius* r = find(kAmber, element)) {
      if (known) *known = true;
      return r->r;
    }
  const Radius* b = find(kBondi, element);
  if (known) *known = set == RadiusSet::Bondi && b;
  return b ? b->r : kFallbackRadius;
}

Molecule read_molecule(const std::string& path, const MoleculeReadOptions& options) {
  std::string text = read_all(path);
  const int digit_elements = is_cif(path) ? 0 : blank_digit_element_columns(text);
  gemmi::Structure st;
  try {
    if (is_cif(path)) {
      gemmi::cif::Document doc = gemmi::cif::read_memory(text.data(), text.size(), path.c_str());
      check_cif_for_gemmi(doc, path);
      st = gemmi::make_structure(std::move(doc));
    } else {
      check_pdb_for_gemmi(text, path);
      pad_connection_records(text);
      check_pdb_record_starts(text, path);
      st = gemmi::read_pdb_from_memory(text.data(), text.size(), path);
    }
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    std::string m = e.what();
    m = m.substr(0, m.find('\n'));
    fail(path, "cannot be read as " + std::string(is_cif(path) ? "mmCIF" : "PDB") + " (" + m + ")");
  }
  Molecule mol;
  mol.path = path;
  mol.model = options.model;
  const bool assembly = !options.assembly.empty() && options.assembly != "none";
  if (assembly) {
    try {
      build_assembly(st, options, path, mol);
    } catch (const Error&) {
      throw;
    } catch (const std::exception& e) {
      std::string m = e.what();
      fail(path, "cannot build assembly " + options.assembly + " (" + m.substr(0, m.find('\n')) + ")");
    }
  } else if (std::string hint = assembly_hint(st); !hint.empty()) {
    mol.warnings.push_back(path + ": " + hint);
  }
  if (st.models.empty()) fail(path, "no atoms (not a PDB/mmCIF coordinate file?)");
  const gemmi::Model* model = nullptr;
  for (auto& m : st.models)
    if (m.name == std::to_string(options.model)) model = &m;
  if (!model && st.models.size() == 1 && options.model == 1) model = &st.models[0];
  if (!model) fail(path, "has no model " + std::to_string(options.model) + " (it has " +
                             std::to_string(st.models.size()) + " model(s))");

  const std::vector<std::string>& ignore = options.ignore_set ? options.ignore : default_ignored_residues();
  std::set<std::string> ignored(ignore.begin(), ignore.end());
  std::set<std::string> chains(options.chains.begin(), options.chains.end());
  std::map<std::string, std::pair<int, double>> unknown;  // element -> (atoms, radius used)
  int total = 0;
  for (const gemmi::Chain& ch : model->chains) {
    for (const gemmi::Residue& res : ch.residues) {
      for (std::size_t ai = 0; ai < res.atoms.size(); ++ai) {
        const gemmi::Atom& a = res.atoms[ai];
        ++total;
        if (!assembly && !chains.empty() && !chains.count(ch.name)) continue;
        if (ignored.count(res.name)) continue;
        if (a.altloc) {  // keep the highest occupancy of the atoms of this name (the first on a tie)
          bool best = true;
          for (std::size_t bi = 0; bi < res.atoms.size() && best; ++bi) {
            const gemmi::Atom& b = res.atoms[bi];
            if (bi == ai || !b.altloc || b.name != a.name) continue;
            if (b.occ > a.occ || (b.occ == a.occ && bi < ai)) best = false;
          }
          if (!best) continue;
        }
        if (!std::isfinite(a.pos.x) || !std::isfinite(a.pos.y) || !std::isfinite(a.pos.z) ||
            std::abs(a.pos.x) > 1e6 || std::abs(a.pos.y) > 1e6 || std::abs(a.pos.z) > 1e6)
          fail(path, "atom " + std::to_string(a.serial) + " (" + a.name + " " + res.name + " " + ch.name +
                         ") has a non-finite or absurd coordinate");
        MolAtom m;
        m.pos = {a.pos.x, a.pos.y, a.pos.z};
        m.element = a.element.uname();
        m.name = a.name;
        m.resname = res.name;
        m.chain = ch.name;
        m.resseq = res.seqid.num.has_value() ? int(res.seqid.num.value) : 0;
        m.icode = res.seqid.icode;
        bool known = true;
        m.radius = element_radius(m.element, options.radii, &known);
        if (!known) {
          auto& u = unknown[m.element];
          u.first += 1;
          u.second = m.radius;
        }
        mol.atoms.push_back(std::move(m));
      }
    }
  }
  mol.ignored_atoms += total - int(mol.atoms.size());
  if (mol.atoms.empty()) {
    if (mol.ignored_atoms == 0) fail(path, "no atoms (not a PDB/mmCIF coordinate file?)");
    fail(path, "no atoms left after the filters (" + std::to_string(mol.ignored_atoms) +
                   " atoms dropped by --chains/--ignore/altlocs)");
  }
  if (int n = digit_elements)
      mol.warnings.push_back(path + ": " + std::to_string(n) +
                             " atom line(s) have digits, not an element, in columns 77-78; elements taken from "
                             "the atom names");
  for (auto& [e, u] : unknown) {
    std::ostringstream s;
    s << path << ": element " << (e.empty() ? "?" : e) << " (" << u.first << " atom(s)) has no "
      << (options.radii == RadiusSet::Amber ? "amber" : "Bondi") << " radius; used " << u.second << " A";
    mol.warnings.push_back(s.str());
  }
  return mol;
}

}  // namespace chokeloops
