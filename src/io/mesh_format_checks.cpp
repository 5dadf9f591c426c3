// The checks of OFF and PLY files before CGAL reads them, and the diagnostics of refused ASCII files
// (mesh_format_checks.h).
#include "mesh_format_checks.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>

#include "chokeloops/grid.h"

namespace chokeloops::detail {
namespace {

std::string q(const std::string& path) { return quoted(path); }

}  // namespace

std::size_t ply_type_size(const std::string& t) {
  if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
  if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
  if (t == "int" || t == "uint" || t == "float" || t == "int32" || t == "uint32" || t == "float32") return 4;
  if (t == "double" || t == "float64") return 8;
  return 0;
}

// A header line as it may be shown in a one-line message: control bytes as '?', at most 60 characters.
std::string printable(std::string s) {
  if (s.size() > 60) s = s.substr(0, 57) + "...";
  for (auto& c : s)
    if (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126) c = '?';
  return s;
}


// A number as CGAL's IO::iformat reads one: with g++ and clang its Input_rep<double> is the stream's own `>>`
// (CGAL scans by hand only for old MSVC, CGAL_FORCE_IFORMAT_DOUBLE), so "0+ 1 2" is one number, then a failure:
// an earlier hand-made scan took three there and let a COFF vertex CGAL reads as one number through (ASan in
// CGAL's colour scan, found by fuzzing).
bool cgal_ascii_double(std::istream& in, double* value) {
  double d = 0;
  if (!(in >> d)) return false;
  if (value) *value = d;
  return true;
}

// CGAL's OFF reader reads the counts of an ASCII header as integers and converts an estimate of the halfedges,
// 2.1 (V + F + 10), to int (undefined beyond INT_MAX, found by fuzzing); a binary header's three big-endian int32
// it takes as they are. The header is scanned here the way CGAL's File_header_OFF scans it (comments, the keyword
// as its letters and digits, then either a count or the word BINARY after more comments: found by fuzzing, a
// keyword ending in a non-alphanumeric byte and BINARY two lines below), and the counts CGAL will take must be
// non-negative and fit the file (ASCII: 2 bytes an item; binary: 12 bytes a vertex, at least 4 a face).
std::string check_off_header(const std::string& path, std::uintmax_t size) {
  std::ifstream in(path, std::ios::binary);
  auto skip_line = [&] {
    char c;
    while (in.get(c) && c != '\n') {
    }
  };
  char c = 0;
  while ((in >> c) && c == '#') skip_line();
  if (!in) return {};  // no header: CGAL refuses it
  std::string keyword(1, c);
  while (keyword.size() < 41 && in.get(c) && std::isalnum(static_cast<unsigned char>(c))) keyword += c;
  std::size_t j = 0;
  const bool textures = keyword.compare(0, 2, "ST") == 0;
  if (textures) j += 2;
  const bool colours = j < keyword.size() && keyword[j] == 'C';
  if (colours) ++j;
  const bool normals = j < keyword.size() && keyword[j] == 'N';
  if (normals) ++j;
  // 4OFF and nOFF (homogeneous, n-dimensional): CGAL reads their headers too (nOFF with one more count first), and
  // doubles the edge count into an int there (overflow, found by fuzzing); their bodies it refuses later itself
  const bool homogeneous = j < keyword.size() && keyword[j] == '4';
  if (homogeneous) ++j;
  const bool dimensional = j < keyword.size() && keyword[j] == 'n';
  if (dimensional) ++j;
  if (keyword.compare(j, std::string::npos, "OFF") != 0) return {};  // not OFF (SKEL, garbage): CGAL refuses it
  auto check_edges = [&](long long edges) {
    if (edges < -1000000000LL || edges > 1000000000LL)
      throw Error(q(path) + ": OFF header announces " + std::to_string(edges) + " edges (malformed)");
  };
  while ((in >> c) && c == '#') skip_line();  // CGAL's skip_comment_OFF, then the next character
  if (!in) return {};
  if (std::isdigit(static_cast<unsigned char>(c))) {  // ASCII counts, read as int by CGAL
    in.unget();
    if (dimensional) {  // the dimension first
      int dimension = 0;
      if (!(in >> dimension)) return {};
    }
    std::uintmax_t counts[2] = {0, 0};
    for (int i = 0; i < 2; ++i) {
      std::string t;
      in >> t;
      if (t.empty() || t.size() > 10 || t.find_first_not_of("0123456789") != std::string::npos)
        throw Error(q(path) + ": malformed OFF header: the " + (i == 0 ? "vertex" : "face") + " count '" +
                    printable(t) + "' is not a non-negative integer");
      counts[i] = std::stoull(t);
    }
    if (counts[0] > size / 2 || counts[1] > size / 2) {
      std::ostringstream s;
      s << q(path) << ": OFF header announces " << counts[0] << " vertices and " << counts[1]
        << " faces, more than a file of " << size << " bytes holds (truncated or malformed)";
      throw Error(s.str());
    }
    // The body, line by line as CGAL's File_scanner_OFF reads it: CGAL converts a face line's numbers, read as
    // double, to std::size_t (its vertex count and indices): undefined for a negative, huge or non-finite number
    // (found by fuzzing: a face of -20 vertices). Such a face is refused here; where CGAL's own reading would
    // fail (no number, the end of the file), the check stops and leaves the message to the reader.
    int edges = 0;
    if (!(in >> edges)) return {};
    check_edges(edges);
    // nOFF: CGAL reads the dimension and then the body as it reads an OFF body (found by fuzzing: a face count of
    // 3.7e20 converted to std::size_t), so the body is checked the same way.
    // Normals, colours and texture coordinates: CGAL's scanner reads a colour past a line's numbers wherever an
    // earlier line had one, and texture coordinates at an index it computes only for coloured files (uninitialised
    // otherwise: UBSan, found by fuzzing, an ST4OFF file). None of them matter here, so CGAL is handed the plain
    // OFF these lines make once checked (coordinates and faces only, numbers written back exactly).
    const bool plain = textures || colours || normals;
    if (plain && homogeneous)
      throw Error(q(path) + ": " + keyword + " (homogeneous coordinates with normals, colours or texture coordinates)"
                  " is not supported: write it as OFF or 4OFF");
    std::ostringstream out;
    out.precision(17);
    if (plain) out << "OFF\n" << counts[0] << ' ' << counts[1] << " 0\n";
    auto next_line = [&](std::string& line) {
      while ((in >> c) && c == '#') skip_line();  // skip_comment_OFF
      if (!in) return false;
      in.unget();
      std::getline(in, line);
      const auto hash = line.find('#');
      if (hash != std::string::npos) line.erase(hash);
      return true;
    };
    // COFF: CGAL takes what follows a vertex's or a face's own numbers as its colour: 1 (an index into its colour
    // map), 3 or 4 numbers, converted to unsigned char (as given, or times 255 when not integers); with 2 it read
    // past the line's numbers (ASan, found by fuzzing). The count and the range are checked here first. CGAL's
    // "has colours" flag, for vertices and for faces, is set by the first line with a colour and never cleared, so
    // it reads a colour for every later line: one without (`seen` true) read past the numbers too (ASan, found by
    // fuzzing: a COFF vertex with a colour, then one without).
    auto check_colour = [&](const std::vector<double>& numbers, std::size_t first, const char* what, std::uintmax_t k,
                            bool& seen) {
      const std::size_t extra = numbers.size() - first;
      if (extra == 0 && seen) {
        std::ostringstream s;
        s << q(path) << ": " << what << " " << k << " has no colour after " << (what[0] == 'v' ? "vertices" : "faces")
          << " with one (in a COFF file, every " << what << " after the first with a colour needs one)";
        throw Error(s.str());
      }
      seen = seen || extra > 0;
      bool ok = extra == 0 || extra == 1 || extra == 3 || extra == 4;
      for (std::size_t i = first; ok && i < numbers.size(); ++i) ok = numbers[i] >= 0 && numbers[i] <= 255;
      if (!ok) {
        std::ostringstream s;
        s << q(path) << ": " << what << " " << k << " has " << extra
          << " colour numbers, or one outside 0-255 (a COFF colour is 1, 3 or 4 numbers)";
        throw Error(s.str());
      }
    };
    // A vertex line with fewer numbers than its coordinates, normal and texture coordinates: CGAL marks the stream
    // bad but still reads the texture coordinates from the line's numbers (found by fuzzing: none, on STOFF).
    const std::size_t needed = (homogeneous ? 4 : 3) + (normals ? 3 : 0) + (textures ? 2 : 0);
    std::string line;
    bool vertex_colours = false, face_colours = false;
    // At the end of the file CGAL's scanner finds no numbers yet still reads a COFF line's colour from them (UBSan,
    // found by fuzzing: a COFF header "1 0 0" and nothing after it), so a truncated COFF file is refused here.
    auto truncated = [&](const char* what, std::uintmax_t k, std::uintmax_t n) {
      std::ostringstream s;
      s << q(path) << ": truncated " << keyword << " file: it ends before " << what << " " << k << " of " << n;
      return Error(s.str());
    };
    // The numbers of the next body line (vertex or face k of n); false where CGAL's own reading fails at the end.
    auto body_line = [&](const char* what, std::uintmax_t k, std::uintmax_t n, std::vector<double>& numbers) {
      if (!next_line(line)) {
        if (plain) throw truncated(what, k, n);
        return false;
      }
      std::istringstream ls(line);
      numbers.clear();
      for (double d; cgal_ascii_double(ls, &d);) numbers.push_back(d);
      return true;
    };
    std::vector<double> numbers_read, entries;
    for (std::uintmax_t v = 0; v < counts[0]; ++v) {
      if (!body_line("vertex", v, counts[0], numbers_read)) return {};
      const std::size_t numbers = numbers_read.size();
      if (colours && numbers >= needed) check_colour(numbers_read, needed, "vertex", v, vertex_colours);
      if (numbers < needed) {
        diagnose_ascii(path, ".off");  // a NaN or infinity among the numbers: named as such
        std::ostringstream s;
        s << q(path) << ": vertex " << v << " has " << numbers << " numbers, fewer than the " << needed << " a "
          << keyword << " vertex needs";
        throw Error(s.str());
      }
      if (plain) out << numbers_read[0] << ' ' << numbers_read[1] << ' ' << numbers_read[2] << '\n';
    }
    for (std::uintmax_t f = 0; f < counts[1]; ++f) {
      if (!body_line("face", f, counts[1], entries)) return {};
      if (entries.empty() && plain) throw Error(q(path) + ": face " + std::to_string(f) + " has no numbers");
      if (entries.empty()) return {};
      auto bad = [&](double d) { return !(d >= 0 && d < 9e18); };
      if (bad(entries[0])) {
        std::ostringstream s;
        s << q(path) << ": face " << f << " has " << entries[0] << " vertices";
        throw Error(s.str());
      }
      const std::size_t n = std::size_t(entries[0]);
      if (n >= entries.size()) {  // CGAL sizes the face by its count before it finds the indices missing
        std::ostringstream s;
        s << q(path) << ": face " << f << " has " << n << " vertices but its line holds " << entries.size() - 1
          << " indices";
        throw Error(s.str());
      }
      if (colours) check_colour(entries, n + 1, "face", f, face_colours);
      for (std::size_t k = 1; k <= n && k < entries.size(); ++k)
        if (bad(entries[k])) {
          std::ostringstream s;
          s << q(path) << ": face " << f << " references vertex " << entries[k];
          throw Error(s.str());
        }
      if (plain) {
        for (std::size_t k = 0; k <= n; ++k) out << std::size_t(entries[k]) << (k < n ? ' ' : '\n');
      }
    }
    return plain ? out.str() : std::string();
  }
  std::string word(1, c);
  while (word.size() < 41 && in.get(c) && std::isalnum(static_cast<unsigned char>(c))) word += c;
  if (word != "BINARY")  // CGAL refuses it too
    throw Error(q(path) + ": malformed OFF header: the vertex count '" + printable(word) +
                "' is not a non-negative integer");
  if (c != '\n') skip_line();
  if (dimensional) {  // the dimension first
    char dimension[4];
    if (!in.read(dimension, 4)) throw Error(q(path) + ": truncated binary OFF header (no vertex and face counts)");
  }
  unsigned char b[12];
  in.read(reinterpret_cast<char*>(b), 12);
  if (in.gcount() < 12) throw Error(q(path) + ": truncated binary OFF header (no vertex and face counts)");
  auto be32 = [&](int i) {
    return std::int32_t(std::uint32_t(b[4 * i]) << 24 | std::uint32_t(b[4 * i + 1]) << 16 |
                        std::uint32_t(b[4 * i + 2]) << 8 | std::uint32_t(b[4 * i + 3]));
  };
  const std::int64_t nv = be32(0), nf = be32(1);
  check_edges(be32(2));
  if (nv < 0 || nf < 0 || std::uintmax_t(nv) * 12 > size || std::uintmax_t(nf) * 4 > size) {
    std::ostringstream s;
    s << q(path) << ": binary OFF header announces " << nv << " vertices and " << nf
      << " faces, which a file of " << size << " bytes cannot hold (truncated or malformed)";
    throw Error(s.str());
  }
  // The faces: CGAL reads each one's vertex count as an int32 into a std::size_t and sizes the face by it before
  // reading its indices, so a negative or huge count (other than -1) allocated up to 16 GB. Each count is checked
  // against what the file has left. Vertices are big-endian floats: 3 coordinates (4 for 4OFF), 3 normal
  // components (4) for N, 2 texture coordinates (3) for ST; COFF colours are not read from binary files.
  const std::uintmax_t per_vertex = 4 * ((homogeneous ? 4 : 3) + (normals ? (homogeneous ? 4 : 3) : 0) +
                                         (textures ? (homogeneous ? 3 : 2) : 0));
  const std::streamoff body = in.tellg();
  // At the end of the file CGAL's binary reads leave their int32 uninitialised and it goes on with it (its check
  // lets a stream at its end pass): a face count read from nothing sized a face at 11 GB (found by fuzzing). A file
  // that ends before its vertices and faces do is refused here.
  auto truncated = [&](const char* what) {
    std::ostringstream s;
    s << q(path) << ": truncated binary OFF file: it ends inside its " << what << " (" << nv << " vertices, " << nf
      << " faces announced)";
    return Error(s.str());
  };
  if (body < 0 || std::uintmax_t(body) + std::uintmax_t(nv) * per_vertex > size) throw truncated("vertices");
  std::uintmax_t at = std::uintmax_t(body) + std::uintmax_t(nv) * per_vertex;
  in.seekg(std::streamoff(at));
  for (std::int64_t f = 0; f < nf; ++f) {
    if (!in.read(reinterpret_cast<char*>(b), 4)) throw truncated("faces");
    at += 4;
    const std::int64_t n = be32(0);
    if (n == -1) return {};  // CGAL's own "no face" check
    if (n < 0 || std::uintmax_t(n) * 4 > size - at) {
      std::ostringstream s;
      s << q(path) << ": binary OFF face " << f << " has " << n << " vertices, more than the " << (size - at)
        << " bytes left in the file hold (truncated or malformed)";
      throw Error(s.str());
    }
    at += std::uintmax_t(n) * 4;
    in.ignore(std::streamsize(n) * 4);  // not seekg: a system call per face
  }
  return {};
}

PlyHeader read_ply_header(const std::string& path) {
  PlyHeader h;
  std::ifstream in(path, std::ios::binary);
  std::string line;
  if (!std::getline(in, line)) return h;
  if (!line.empty() && line.back() == '\r') line.pop_back();
  if (line != "ply") throw Error(q(path) + ": not a PLY file (first line is not 'ply')");
  std::size_t count = 0;
  std::size_t lineno = 1;  // header lines read, counting comments (CGAL's numbering)
  std::string current;
  std::size_t fixed = 0, lists_min = 0;  // per element of `current`
  auto close_element = [&] {
    if (current.empty()) return;
    // An item without properties reads nothing, so its count is bounded by nothing in the file: CGAL made 1.8e9
    // points from a 219-byte file whose vertex element's properties were all on its own line (a timeout, found by
    // fuzzing). A header announcing items of an element without properties is malformed.
    if (count > 0 && h.elements.back().properties.empty()) {
      std::ostringstream s;
      s << q(path) << ": PLY element '" << printable(current) << "' announces " << count
        << " items but declares no property (malformed header)";
      throw Error(s.str());
    }
    h.min_body_bytes += count * (fixed + lists_min);
    if (current == "vertex") { h.vertex_count = count; h.has_vertex = true; }
    if (current == "face") { h.face_count = count; h.has_face = true; }
  };
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream ls(line);
    std::string kw;
    ls >> kw;
    // CGAL's PLY reader trusts the header's grammar (a property before any element crashes it): check it here.
    if (kw.empty()) throw Error(q(path) + ": PLY header has an empty line");
    if (kw == "comment" || kw == "obj_info") {
      ++lineno;
      continue;
    }
    if (kw != "format" && kw != "element" && kw != "property" && kw != "end_header")
      throw Error(q(path) + ": malformed PLY header line '" + printable(line) + "'");
    if (kw == "property" && current.empty())
      throw Error(q(path) + ": PLY header has a property before any element");
    ++lineno;
    // CGAL takes the format from the second line and ignores format lines elsewhere: so must this check
    if (kw == "format" && lineno != 2)
      throw Error(q(path) + ": PLY header has a format line other than its second line");
    if (lineno == 2 && kw != "format") throw Error(q(path) + ": PLY header's second line is not its format");
    if (kw == "format") ls >> h.format;
    else if (kw == "element") {
      close_element();
      current.clear();
      long long c = -1;
      ls >> current >> c;
      if (c < 0) throw Error(q(path) + ": malformed PLY header line '" + line + "'");
      count = std::size_t(c);
      fixed = lists_min = 0;
      h.elements.push_back({count, {}});
    } else if (kw == "property") {
      std::string t;
      ls >> t;
      if (t == "list") {
        std::string ct, it;
        ls >> ct >> it;
        if (!ply_type_size(ct) || !ply_type_size(it))
          throw Error(q(path) + ": PLY header line '" + printable(line) + "' names an unknown type");
        if (ct == "float" || ct == "float32" || ct == "double" || ct == "float64")
          throw Error(q(path) + ": PLY header line '" + printable(line) + "' gives a list a floating-point count");
        // the list count itself, plus at least 3 indices for a face
        lists_min += ply_type_size(ct) + (current == "face" ? 3 * ply_type_size(it) : 0);
        h.elements.back().properties.push_back({it, ct});
      } else {
        if (!ply_type_size(t)) throw Error(q(path) + ": PLY header line '" + printable(line) + "' names an unknown type");
        fixed += ply_type_size(t);
        h.elements.back().properties.push_back({t, ""});
      }
    } else if (kw == "end_header") {
      close_element();
      h.ok = true;
      h.header_bytes = std::size_t(in.tellg());
      return h;
    }
  }
  throw Error(q(path) + ": truncated PLY header (no end_header)");
}

// CGAL's PLY reader sizes each list by the count the file gives (vector::resize) before reading its items: a count
// of 2^31 in a file of 700 bytes allocated 8 GB (found by fuzzing). The body is walked here first, element by
// element as CGAL reads it (binary: the declared sizes and byte order; ASCII: the same extractions, `>>` for
// integers and floating point alike), and a list longer than what the file has left is refused. Where
// CGAL's own reading would fail (a bad number, the end of the file, a negative count, which vector refuses), the walk
// stops and leaves the message to the reader.
bool ply_integer_type(const std::string& t) { return t != "float" && t != "float32" && t != "double" && t != "float64"; }
bool ply_signed_type(const std::string& t) {
  return t == "char" || t == "int8" || t == "short" || t == "int16" || t == "int" || t == "int32";
}

// An ASCII number as CGAL's PLY reader extracts one of type `t`: false where CGAL's extraction fails.
bool ply_ascii_number(std::istream& in, const std::string& t, long long* value) {
  if (t == "float" || t == "float32") {  // CGAL extracts a float: beyond its range the extraction fails
    float f = 0;
    return bool(in >> f);
  }
  if (!ply_integer_type(t)) return cgal_ascii_double(in, nullptr);
  const std::size_t size = ply_type_size(t);
  const bool is_signed = ply_signed_type(t);
  // A failed extraction still stores a value (0 without digits, the type's limit on overflow), and CGAL sizes a list
  // by it before it looks at the stream: `value` is that value either way (found by fuzzing: a list count of 42
  // digits became INT_MAX, 2 GB of items).
  long long v = 0;
  bool ok = true;
  if (size == 1 && is_signed) { short x = 0; ok = bool(in >> x); v = static_cast<signed char>(x); }
  else if (size == 1) { unsigned short x = 0; ok = bool(in >> x); v = static_cast<unsigned char>(x); }
  else if (size == 2 && is_signed) { short x = 0; ok = bool(in >> x); v = x; }
  else if (size == 2) { unsigned short x = 0; ok = bool(in >> x); v = x; }
  else if (is_signed) { std::int32_t x = 0; ok = bool(in >> x); v = x; }
  else { std::uint32_t x = 0; ok = bool(in >> x); v = x; }
  if (value) *value = v;
  return ok;
}

void check_ply_lists(const std::string& path, const PlyHeader& h, std::uintmax_t size) {
  std::ifstream in(path, std::ios::binary);
  in.seekg(std::streamoff(h.header_bytes));
  const bool ascii = h.format == "ascii", big = h.format == "binary_big_endian";
  if (!ascii && !big && h.format != "binary_little_endian") return;  // CGAL refuses other formats itself
  // The binary position is counted here, not asked of the stream: a tellg or seekg per face is a system call
  // each (a 411K-face PLY took 3 s to check).
  std::uintmax_t pos = h.header_bytes;
  auto left = [&]() -> std::uintmax_t {
    if (!ascii) return pos >= size ? 0 : size - pos;
    const std::streamoff here = in.tellg();
    return here < 0 || std::uintmax_t(here) >= size ? 0 : size - std::uintmax_t(here);
  };
  auto skip = [&](std::uintmax_t bytes) {
    in.ignore(std::streamsize(bytes));
    pos += bytes;
  };
  auto refuse = [&](long long count, std::size_t element) {
    std::ostringstream s;
    s << q(path) << ": PLY list of " << count << " items in element " << element
      << " is longer than the rest of the file (truncated or malformed)";
    throw Error(s.str());
  };
  // Once a read fails (the file ends, or a token is not a number), CGAL goes on reading the element's other
  // properties from the failed stream, which leaves each value untouched: a list count then is whatever the
  // uninitialised variable held (found by fuzzing: a 2e9-item list from an ASCII file ending inside its vertices,
  // only now and then). So where a list is still to come, a body that fails is refused here.
  std::vector<bool> list_ahead(h.elements.size() + 1, false);
  for (std::size_t e = h.elements.size(); e-- > 0;) {
    list_ahead[e] = list_ahead[e + 1];
    for (const auto& p : h.elements[e].properties) list_ahead[e] = list_ahead[e] || !p.count_type.empty();
  }
  auto stop = [&](std::size_t e, std::size_t i) {
    if (!list_ahead[e]) return;  // CGAL finds the failure itself, before any list
    std::ostringstream s;
    s << q(path) << ": " << (ascii ? "ASCII" : "binary") << " PLY body ends or holds something other than a number in "
      << "element " << e << ", item " << i << ", before a list's count (truncated or malformed)";
    throw Error(s.str());
  };
  for (std::size_t e = 0; e < h.elements.size(); ++e) {
    const PlyHeader::Element& el = h.elements[e];
    if (el.properties.empty()) continue;
    std::size_t fixed = 0;
    bool lists = false;
    for (const auto& p : el.properties) {
      lists = lists || !p.count_type.empty();
      fixed += ply_type_size(p.type);
    }
    if (!ascii && !lists) {  // binary, fixed size: skip the whole element
      if (std::uintmax_t(fixed) * el.count > left()) return stop(e, std::size_t(left() / std::max<std::size_t>(fixed, 1)));
      pos += std::uintmax_t(fixed) * el.count;
      in.seekg(std::streamoff(pos));
      continue;
    }
    for (std::size_t i = 0; i < el.count; ++i)  // each instance takes at least one byte: ends with the file
      for (const auto& p : el.properties) {
        const std::size_t item = ply_type_size(p.type);
        if (ascii) {
          long long n = 1;
          const bool read = ply_ascii_number(in, p.count_type.empty() ? p.type : p.count_type, &n);
          // an item and a separator each; short lists need no check (and a tellg each)
          if (!p.count_type.empty() && n > 1024 && std::uintmax_t(n) > left() / 2 + 1) refuse(n, e);
          if (!read) return stop(e, i);
          if (p.count_type.empty()) continue;
          if (n < 0) return;
          for (long long k = 0; k < n; ++k)
            if (!ply_ascii_number(in, p.type, nullptr)) return stop(e, i);
          continue;
        }
        if (p.count_type.empty()) {
          if (item > left()) return stop(e, i);
          skip(item);
          continue;
        }
        const std::size_t cs = ply_type_size(p.count_type);
        unsigned char b[4] = {0, 0, 0, 0};
        if (cs > left() || !in.read(reinterpret_cast<char*>(b), std::streamsize(cs))) return stop(e, i);
        pos += cs;
        std::uint32_t u = 0;
        for (std::size_t k = 0; k < cs; ++k) u |= std::uint32_t(b[big ? cs - 1 - k : k]) << (8 * k);
        long long n = u;
        if (ply_signed_type(p.count_type) && (u >> (8 * cs - 1)) & 1u) return;  // negative
        if (std::uintmax_t(n) * item > left()) refuse(n, e);
        skip(std::uintmax_t(n) * item);
      }
  }
}


// ---- diagnostics for ASCII files CGAL refused: find the first non-finite number ----
void diagnose_ascii(const std::string& path, const std::string& ext) {
  std::ifstream in(path);
  std::string line;
  std::size_t lineno = 0;
  while (std::getline(in, line) && lineno < 50000000) {
    ++lineno;
    std::istringstream ls(line);
    std::string tok;
    while (ls >> tok) {
      std::string t = tok;
      for (auto& c : t) c = char(std::tolower(static_cast<unsigned char>(c)));
      if (!t.empty() && (t[0] == '-' || t[0] == '+')) t = t.substr(1);
      if (t == "nan" || t == "inf" || t == "infinity" || t.rfind("nan(", 0) == 0)
        throw Error(q(path) + ": non-finite coordinate '" + tok + "' on line " + std::to_string(lineno));
    }
  }
  diagnose_faces(path, ext);
}

// OBJ / OFF: faces referencing missing vertices, or no faces at all.
void diagnose_faces(const std::string& path, const std::string& ext) {
  std::ifstream in(path);
  std::string line;
  auto bad_index = [&](long long idx, long long nv, std::size_t face) {
    std::ostringstream s;
    s << q(path) << ": face " << face << " references vertex " << idx << " but the file has only " << nv
      << " vertices";
    throw Error(s.str());
  };
  if (ext == ".obj") {
    long long nv = 0;
    std::size_t nf = 0;
    std::vector<std::string> faces;
    while (std::getline(in, line)) {
      std::istringstream ls(line);
      std::string kw;
      ls >> kw;
      if (kw == "v") ++nv;
      else if (kw == "f") {
        std::string tok;
        while (ls >> tok) {
          long long idx = std::atoll(tok.c_str());  // "i/t/n" → i
          long long abs_idx = idx < 0 ? nv + idx + 1 : idx;
          if (idx == 0 || abs_idx < 1 || abs_idx > nv) bad_index(idx, nv, nf);
        }
        ++nf;
      }
    }
    if (nf == 0) throw Error(q(path) + ": no faces (" + std::to_string(nv) + " vertices, 0 faces)");
  } else if (ext == ".off") {
    std::vector<std::string> toks;
    std::string tok;
    // tokens without comments
    while (std::getline(in, line)) {
      auto hash = line.find('#');
      if (hash != std::string::npos) line.resize(hash);
      std::istringstream ls(line);
      while (ls >> tok) toks.push_back(tok);
      if (toks.size() > 50000000) return;
    }
    std::size_t t = 0;
    if (t < toks.size() && toks[t].find("OFF") != std::string::npos) ++t;
    if (t + 3 > toks.size()) return;
    auto is_int = [](const std::string& x) {
      return !x.empty() && std::all_of(x.begin(), x.end(), [](char c) { return std::isdigit(static_cast<unsigned char>(c)); });
    };
    if (!is_int(toks[t]) || !is_int(toks[t + 1]) || !is_int(toks[t + 2])) return;
    long long nv = std::atoll(toks[t].c_str()), nf = std::atoll(toks[t + 1].c_str());
    t += 3;
    if (nf == 0) throw Error(q(path) + ": no faces (" + std::to_string(nv) + " vertices, 0 faces)");
    t += std::size_t(std::max(0LL, nv)) * 3;
    for (long long f = 0; f < nf && t < toks.size(); ++f) {
      long long k = std::atoll(toks[t++].c_str());
      for (long long j = 0; j < k && t < toks.size(); ++j) {
        long long idx = std::atoll(toks[t++].c_str());
        if (idx < 0 || idx >= nv) bad_index(idx, nv, std::size_t(f));
      }
      // skip optional colour values up to the next face: not handled (rare); stop at mismatch
    }
    if (t < toks.size() && std::size_t(nv) * 3 + 3 < toks.size()) return;
    if (toks.size() < t) throw Error(q(path) + ": truncated OFF file");
  }
}

}  // namespace chokeloops::detail
