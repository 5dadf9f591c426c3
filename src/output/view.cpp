// OUTDIR/view.html and its PNG: see include/chokeloops/output/view.h. The page itself (HTML template and the
// bundled three.js viewer, viewer/) is compiled in by cmake/viewer.cmake as two string literals.
#include "chokeloops/output/view.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string_view>
#include <thread>
#include <unordered_map>

#include "chokeloops/grid.h"

namespace chokeloops {
namespace view_detail {
extern const std::string_view kViewerTemplate;
extern const std::string_view kViewerBundle;
}  // namespace view_detail

namespace fs = std::filesystem;
using view_detail::TriMesh;

namespace {

std::string read_file(const fs::path& p, const char* what) {
  std::ifstream in(p, std::ios::binary);
  if (!in) throw Error("cannot read " + p.string() + " (" + what + "); run `chokeloops analyze INPUT -o OUTDIR` first");
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// ---------------------------------------------------------------------------------------------- PLY
enum class PlyType { i8, u8, i16, u16, i32, u32, f32, f64 };

PlyType ply_type(const std::string& t, const std::string& path) {
  if (t == "char" || t == "int8") return PlyType::i8;
  if (t == "uchar" || t == "uint8") return PlyType::u8;
  if (t == "short" || t == "int16") return PlyType::i16;
  if (t == "ushort" || t == "uint16") return PlyType::u16;
  if (t == "int" || t == "int32") return PlyType::i32;
  if (t == "uint" || t == "uint32") return PlyType::u32;
  if (t == "float" || t == "float32") return PlyType::f32;
  if (t == "double" || t == "float64") return PlyType::f64;
  throw Error(path + ": unknown PLY property type '" + t + "'");
}
std::size_t ply_size(PlyType t) {
  switch (t) {
    case PlyType::i8: case PlyType::u8: return 1;
    case PlyType::i16: case PlyType::u16: return 2;
    case PlyType::i32: case PlyType::u32: case PlyType::f32: return 4;
    case PlyType::f64: return 8;
  }
  return 0;
}

struct PlyProperty {
  std::string name;
  bool is_list = false;
  PlyType count_type = PlyType::u8, type = PlyType::f32;
};
struct PlyElement {
  std::string name;
  std::size_t count = 0;
  std::vector<PlyProperty> props;
};

class PlyBody {
 public:
  PlyBody(const std::string& data, std::size_t pos, int format, std::string path)
      : d_(data), pos_(pos), format_(format), path_(std::move(path)) {}
  double read(PlyType t) {
    if (format_ == 0) return read_ascii();
    std::size_t n = ply_size(t);
    if (pos_ + n > d_.size()) throw Error(path_ + ": PLY file is truncated");
    unsigned char b[8];
    std::memcpy(b, d_.data() + pos_, n);
    pos_ += n;
    if (format_ == 2) std::reverse(b, b + n);
    switch (t) {
      case PlyType::i8: { std::int8_t v; std::memcpy(&v, b, 1); return v; }
      case PlyType::u8: return b[0];
      case PlyType::i16: { std::int16_t v; std::memcpy(&v, b, 2); return v; }
      case PlyType::u16: { std::uint16_t v; std::memcpy(&v, b, 2); return v; }
      case PlyType::i32: { std::int32_t v; std::memcpy(&v, b, 4); return v; }
      case PlyType::u32: { std::uint32_t v; std::memcpy(&v, b, 4); return v; }
      case PlyType::f32: { float v; std::memcpy(&v, b, 4); return v; }
      case PlyType::f64: { double v; std::memcpy(&v, b, 8); return v; }
    }
    return 0;
  }

 private:
  double read_ascii() {
    while (pos_ < d_.size() && std::isspace(static_cast<unsigned char>(d_[pos_]))) ++pos_;
    if (pos_ >= d_.size()) throw Error(path_ + ": PLY file is truncated");
    const char* begin = d_.c_str() + pos_;
    char* end = nullptr;
    double v = std::strtod(begin, &end);
    if (end == begin) throw Error(path_ + ": bad number in ascii PLY body near byte " + std::to_string(pos_));
    pos_ += static_cast<std::size_t>(end - begin);
    return v;
  }
  const std::string& d_;
  std::size_t pos_;
  int format_;  // 0 ascii, 1 little endian, 2 big endian
  std::string path_;
};

// ---------------------------------------------------------------------------------------------- base64
std::string base64(const void* data, std::size_t n) {
  static const char* abc = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  const auto* p = static_cast<const unsigned char*>(data);
  std::string out;
  out.reserve((n + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 3 <= n; i += 3) {
    std::uint32_t v = (p[i] << 16) | (p[i + 1] << 8) | p[i + 2];
    out += abc[v >> 18]; out += abc[(v >> 12) & 63]; out += abc[(v >> 6) & 63]; out += abc[v & 63];
  }
  if (n - i == 1) {
    std::uint32_t v = p[i] << 16;
    out += abc[v >> 18]; out += abc[(v >> 12) & 63]; out += "==";
  } else if (n - i == 2) {
    std::uint32_t v = (p[i] << 16) | (p[i + 1] << 8);
    out += abc[v >> 18]; out += abc[(v >> 12) & 63]; out += abc[(v >> 6) & 63]; out += '=';
  }
  return out;
}

std::string html_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

// JSON placed inside <script>: '<' only occurs inside strings there, where \u003c is the same character.
std::string script_safe_json(const nlohmann::json& j) {
  std::string s = j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  std::string out;
  out.reserve(s.size());
  for (char c : s) {
    if (c == '<') out += "\\u003c";
    else out += c;
  }
  return out;
}

// JavaScript placed inside <script>: "</script" would end the element early.
std::string script_safe_js(std::string_view js) {
  std::string out(js);
  for (std::size_t p = 0; (p = out.find("</", p)) != std::string::npos; p += 3) out.replace(p, 2, "<\\/");
  return out;
}

std::string url_for(const fs::path& file) {
  static const char* hex = "0123456789ABCDEF";
  std::string out = "file://";
  for (unsigned char c : file.string()) {
    if (std::isalnum(c) || c == '/' || c == '-' || c == '_' || c == '.' || c == '~') out += static_cast<char>(c);
    else { out += '%'; out += hex[c >> 4]; out += hex[c & 15]; }
  }
  return out;
}

}  // namespace

// ---------------------------------------------------------------------------------------------- mesh
namespace view_detail {

TriMesh read_ply(const std::string& path) {
  std::string data = read_file(path, "the surface mesh written by analyze");
  if (data.compare(0, 3, "ply") != 0) throw Error(path + ": not a PLY file (no 'ply' magic)");
  int format = -1;
  std::vector<PlyElement> elements;
  std::size_t pos = 0;
  bool ended = false;
  while (pos < data.size()) {
    std::size_t eol = data.find('\n', pos);
    if (eol == std::string::npos) break;
    std::string line = data.substr(pos, eol - pos);
    pos = eol + 1;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream ls(line);
    std::string word;
    ls >> word;
    if (word == "format") {
      std::string f;
      ls >> f;
      if (f == "ascii") format = 0;
      else if (f == "binary_little_endian") format = 1;
      else if (f == "binary_big_endian") format = 2;
      else throw Error(path + ": unknown PLY format '" + f + "'");
    } else if (word == "element") {
      PlyElement e;
      ls >> e.name >> e.count;
      if (!ls) throw Error(path + ": bad PLY header line '" + line + "'");
      elements.push_back(e);
    } else if (word == "property") {
      if (elements.empty()) throw Error(path + ": PLY property before any element");
      PlyProperty p;
      std::string t;
      ls >> t;
      if (t == "list") {
        std::string ct, it;
        ls >> ct >> it >> p.name;
        p.is_list = true;
        p.count_type = ply_type(ct, path);
        p.type = ply_type(it, path);
      } else {
        ls >> p.name;
        p.type = ply_type(t, path);
      }
      elements.back().props.push_back(p);
    } else if (word == "end_header") {
      ended = true;
      break;
    }
  }
  if (!ended || format < 0) throw Error(path + ": incomplete PLY header (no format or end_header)");

  TriMesh mesh;
  PlyBody body(data, pos, format, path);
  bool have_vertices = false;
  for (const auto& e : elements) {
    int ix = -1, iy = -1, iz = -1, ifaces = -1;
    for (std::size_t k = 0; k < e.props.size(); ++k) {
      const auto& n = e.props[k].name;
      if (e.name == "vertex" && !e.props[k].is_list) {
        if (n == "x") ix = int(k);
        if (n == "y") iy = int(k);
        if (n == "z") iz = int(k);
      }
      if (e.name == "face" && e.props[k].is_list && (n == "vertex_indices" || n == "vertex_index")) ifaces = int(k);
    }
    if (e.name == "vertex") {
      if (ix < 0 || iy < 0 || iz < 0) throw Error(path + ": PLY vertex element lacks x, y or z");
      mesh.vertices.reserve(e.count);
      have_vertices = true;
    }
    if (e.name == "face" && ifaces < 0) throw Error(path + ": PLY face element lacks vertex_indices");
    if (e.name == "face") mesh.faces.reserve(e.count * 1);
    std::vector<std::uint32_t> poly;
    for (std::size_t r = 0; r < e.count; ++r) {
      std::array<float, 3> v{0, 0, 0};
      for (std::size_t k = 0; k < e.props.size(); ++k) {
        const auto& p = e.props[k];
        if (p.is_list) {
          double cnt = body.read(p.count_type);
          if (cnt < 0 || cnt > 1e6) throw Error(path + ": bad PLY list length");
          poly.clear();
          for (std::size_t c = 0; c < std::size_t(cnt); ++c) {
            double x = body.read(p.type);
            if (int(k) == ifaces) {
              if (!(x >= 0 && x < 4294967295.0)) throw Error(path + ": PLY face " + std::to_string(r) + " has a bad vertex index");
              poly.push_back(static_cast<std::uint32_t>(x));
            }
          }
          if (int(k) == ifaces) {
            for (std::size_t c = 1; c + 1 < poly.size(); ++c) mesh.faces.push_back({poly[0], poly[c], poly[c + 1]});
          }
        } else {
          double x = body.read(p.type);
          if (e.name == "vertex") {
            if (int(k) == ix) v[0] = float(x);
            if (int(k) == iy) v[1] = float(x);
            if (int(k) == iz) v[2] = float(x);
          }
        }
      }
      if (e.name == "vertex") {
        if (!std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2]))
          throw Error(path + ": non-finite vertex coordinate at vertex " + std::to_string(r));
        mesh.vertices.push_back(v);
      }
    }
  }
  if (!have_vertices) throw Error(path + ": PLY file has no vertex element");
  for (const auto& f : mesh.faces)
    for (auto i : f)
      if (i >= mesh.vertices.size()) throw Error(path + ": PLY face refers to vertex " + std::to_string(i) + " of " + std::to_string(mesh.vertices.size()));
  return mesh;
}

double decimate(TriMesh& mesh, std::size_t max_faces) {
  if (mesh.faces.size() <= max_faces || mesh.vertices.empty()) return 0.0;
  std::array<double, 3> lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  for (const auto& v : mesh.vertices)
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], double(v[a])), hi[a] = std::max(hi[a], double(v[a]));
  double area = 0;
  for (const auto& f : mesh.faces) {
    const auto &a = mesh.vertices[f[0]], &b = mesh.vertices[f[1]], &c = mesh.vertices[f[2]];
    double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    double x = u[1] * w[2] - u[2] * w[1], y = u[2] * w[0] - u[0] * w[2], z = u[0] * w[1] - u[1] * w[0];
    area += 0.5 * std::sqrt(x * x + y * y + z * z);
  }
  double extent = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], 1e-30});
  // A surface of area A clustered with cells of size h keeps roughly 2A/h^2 to 4A/h^2 faces.
  if (!std::isfinite(extent) || !std::isfinite(area)) throw Error("the surface is too large to display (coordinates overflow)");
  double h = std::max(std::sqrt(3.0 * area / double(max_faces)), extent / 2000000.0);
  if (!(h > 0)) h = extent > 0 ? extent / 1000.0 : 1.0;
  for (int attempt = 0; attempt < 60; ++attempt, h *= 1.15) {
    std::unordered_map<std::uint64_t, std::uint32_t> cell_of;
    cell_of.reserve(mesh.vertices.size() / 2);
    std::vector<std::uint32_t> remap(mesh.vertices.size());
    std::vector<std::array<double, 4>> sums;
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
      const auto& v = mesh.vertices[i];
      std::uint64_t key = 0;
      for (int a = 0; a < 3; ++a) key = (key << 21) | std::uint64_t(std::clamp((v[a] - lo[a]) / h, 0.0, double(0x1FFFFF)));
      auto [it, fresh] = cell_of.emplace(key, std::uint32_t(sums.size()));
      if (fresh) sums.push_back({0, 0, 0, 0});
      auto& s = sums[it->second];
      s[0] += v[0]; s[1] += v[1]; s[2] += v[2]; s[3] += 1;
      remap[i] = it->second;
    }
    std::vector<std::array<float, 3>> verts(sums.size());
    for (std::size_t i = 0; i < sums.size(); ++i)
      verts[i] = {float(sums[i][0] / sums[i][3]), float(sums[i][1] / sums[i][3]), float(sums[i][2] / sums[i][3])};
    auto normal = [](const std::array<float, 3>& a, const std::array<float, 3>& b, const std::array<float, 3>& c) {
      double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
      return std::array<double, 3>{u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
    };
    std::vector<std::array<std::uint32_t, 3>> faces;
    faces.reserve(mesh.faces.size() / 2);
    for (const auto& f : mesh.faces) {
      std::array<std::uint32_t, 3> g{remap[f[0]], remap[f[1]], remap[f[2]]};
      if (g[0] == g[1] || g[1] == g[2] || g[0] == g[2]) continue;
      // Drop faces that clustering folded over (they shade as dark specks).
      auto n0 = normal(mesh.vertices[f[0]], mesh.vertices[f[1]], mesh.vertices[f[2]]);
      auto n1 = normal(verts[g[0]], verts[g[1]], verts[g[2]]);
      if (n0[0] * n1[0] + n0[1] * n1[1] + n0[2] * n1[2] <= 0) continue;
      std::rotate(g.begin(), std::min_element(g.begin(), g.end()), g.end());  // canonical, orientation kept
      faces.push_back(g);
    }
    std::sort(faces.begin(), faces.end());
    faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
    if (faces.size() > max_faces) continue;
    mesh.vertices = std::move(verts);
    mesh.faces = std::move(faces);
    return h;
  }
  throw Error("could not decimate the surface below " + std::to_string(max_faces) + " faces for display");
}

}  // namespace view_detail

// ---------------------------------------------------------------------------------------------- page
void write_view_html(const std::string& outdir, std::size_t face_budget) {
  if (view_detail::kViewerBundle.empty())
    throw Error("this chokeloops was built without its viewer bundle: run scripts/build-viewer.sh (needs Node.js "
                "and npm) and rebuild", 3);
  fs::path dir(outdir);
  if (!fs::is_directory(dir)) throw Error("no such output directory: " + outdir);
  fs::path ply = dir / "surface.ply", json_path = dir / "loops.json";
  if (!fs::exists(json_path)) throw Error("missing " + json_path.string() + "; run `chokeloops analyze INPUT -o " + outdir + "` first");
  if (!fs::exists(ply)) throw Error("missing " + ply.string() + "; run `chokeloops analyze INPUT -o " + outdir + "` first");

  nlohmann::json report;
  try {
    report = nlohmann::json::parse(read_file(json_path, "the loops report written by analyze"));
  } catch (const nlohmann::json::exception& e) {
    throw Error(json_path.string() + " is not valid JSON: " + e.what());
  }
  if (!report.is_object()) throw Error(json_path.string() + ": expected a JSON object");
  if (report.contains("loops")) {
    if (!report["loops"].is_array()) throw Error(json_path.string() + ": \"loops\" must be an array");
    for (const auto& l : report["loops"])
      if (!l.is_object() || !l.contains("points") || !l["points"].is_array())
        throw Error(json_path.string() + ": every loop needs a \"points\" array");
  }

  TriMesh mesh = view_detail::read_ply(ply.string());
  std::size_t source_faces = mesh.faces.size(), source_vertices = mesh.vertices.size();
  double cell = face_budget == 0 ? 0.0 : view_detail::decimate(mesh, face_budget);

  nlohmann::json data;
  data["report"] = std::move(report);
  data["mesh"] = {{"source_vertices", source_vertices}, {"source_faces", source_faces},
                  {"display_vertices", mesh.vertices.size()}, {"display_faces", mesh.faces.size()},
                  {"decimated", cell > 0}, {"cell_size", cell}, {"face_budget", face_budget}};
  // A mesh input's loops on its own triangles (input_loops.json on input_mesh.ply): the page can show those
  // instead of the marching surface's.
  TriMesh input_mesh;
  fs::path input_json = dir / "input_loops.json", input_ply = dir / "input_mesh.ply";
  if (fs::exists(input_json) && fs::exists(input_ply)) {
    nlohmann::json input;
    try {
      input = nlohmann::json::parse(read_file(input_json, "the input loops written by analyze"));
    } catch (const nlohmann::json::exception& e) {
      throw Error(input_json.string() + " is not valid JSON: " + e.what());
    }
    if (!input.is_object() || !input.contains("loops") || !input["loops"].is_array())
      throw Error(input_json.string() + ": expected an object with a \"loops\" array");
    for (const auto& l : input["loops"])
      if (!l.is_object() || !l.contains("points") || !l["points"].is_array())
        throw Error(input_json.string() + ": every loop needs a \"points\" array");
    input_mesh = view_detail::read_ply(input_ply.string());
    const std::size_t faces = input_mesh.faces.size(), vertices = input_mesh.vertices.size();
    const double input_cell = face_budget == 0 ? 0.0 : view_detail::decimate(input_mesh, face_budget);
    nlohmann::json loops = nlohmann::json::array();
    for (auto& l : input["loops"]) {  // the page needs what loops.json has, not the ids on the input
      l.erase("input_points");
      l.erase("edge_path");
      loops.push_back(std::move(l));
    }
    data["input_view"] = {{"loops", std::move(loops)},
                          {"mesh", {{"source_vertices", vertices}, {"source_faces", faces}, {"display_vertices", input_mesh.vertices.size()},
                                    {"display_faces", input_mesh.faces.size()}, {"decimated", input_cell > 0}, {"cell_size", input_cell},
                                    {"face_budget", face_budget}}}};
  }
  std::string title = data["report"].value("input", std::string("analysis"));
  if (!data["report"]["input"].is_string()) title = "analysis";

  static_assert(sizeof(std::array<float, 3>) == 12 && sizeof(std::array<std::uint32_t, 3>) == 12);
  std::unordered_map<std::string, std::string> fill = {
      {"VERSION", CHOKELOOPS_VERSION},
      {"TITLE", html_escape(title)},
      {"DATA", script_safe_json(data)},
      {"POSITIONS", base64(mesh.vertices.data(), mesh.vertices.size() * 12)},  // little-endian float32
      {"INDICES", base64(mesh.faces.data(), mesh.faces.size() * 12)},          // little-endian uint32
      {"INPUT_POSITIONS", base64(input_mesh.vertices.data(), input_mesh.vertices.size() * 12)},
      {"INPUT_INDICES", base64(input_mesh.faces.data(), input_mesh.faces.size() * 12)},
      {"BUNDLE", script_safe_js(view_detail::kViewerBundle)},
  };
  std::string html;
  std::string_view t = view_detail::kViewerTemplate;
  html.reserve(t.size() + fill["POSITIONS"].size() + fill["INDICES"].size() + fill["INPUT_POSITIONS"].size() +
               fill["INPUT_INDICES"].size() + fill["BUNDLE"].size() + fill["DATA"].size());
  for (std::size_t p = 0;;) {
    std::size_t a = t.find("{{", p);
    std::size_t b = a == std::string_view::npos ? a : t.find("}}", a);
    auto it = b == std::string_view::npos ? fill.end() : fill.find(std::string(t.substr(a + 2, b - a - 2)));
    if (it == fill.end()) {
      if (a == std::string_view::npos) { html.append(t.substr(p)); break; }
      html.append(t.substr(p, a + 2 - p));
      p = a + 2;
      continue;
    }
    html.append(t.substr(p, a - p));
    html.append(it->second);
    p = b + 2;
  }

  fs::path out = dir / "view.html", tmp = dir / "view.html.tmp";
  {
    std::ofstream f(tmp, std::ios::binary);
    f.write(html.data(), std::streamsize(html.size()));
    if (!f) throw Error("cannot write " + tmp.string(), 3);
  }
  fs::rename(tmp, out);
}

// ---------------------------------------------------------------------------------------------- PNG
std::string find_chromium() {
  auto executable = [](const fs::path& p) { return ::access(p.c_str(), X_OK) == 0 && !fs::is_directory(p); };
  if (const char* env = std::getenv("CHOKELOOPS_CHROMIUM"); env && *env) return executable(env) ? std::string(env) : std::string();
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "/usr/local/bin:/usr/bin:/bin";
  for (const char* name : {"chromium", "chromium-browser", "google-chrome", "google-chrome-stable"}) {
    std::stringstream ss(dirs);
    std::string d;
    while (std::getline(ss, d, ':')) {
      if (d.empty()) continue;
      fs::path p = fs::path(d) / name;
      if (executable(p)) return p.string();
    }
  }
  return {};
}

std::vector<std::string> chromium_flags(int width, int height) {
  return {"--headless", "--no-sandbox", "--disable-gpu", "--no-first-run", "--disable-background-networking",
          "--disable-component-update", "--disable-sync", "--disable-quic", "--disable-extensions",
          "--disable-default-apps", "--disable-dev-shm-usage", "--hide-scrollbars", "--mute-audio", "--force-device-scale-factor=1",
          "--enable-unsafe-swiftshader",  // software WebGL on machines without a GPU, for this local page only
          "--window-size=" + std::to_string(width) + "," + std::to_string(height)};
}

void render_png(const std::string& outdir, const std::string& png_path, int width, int height) {
  if (width < 16 || height < 16 || width > 8192 || height > 8192)
    throw Error("picture size " + std::to_string(width) + "x" + std::to_string(height) + " is out of range (16..8192)");
  if (!fs::is_directory(outdir)) throw Error("no such output directory: " + outdir);
  std::string chromium = find_chromium();
  if (chromium.empty())
    throw Error("rendering a PNG needs Chromium, which was not found: install Debian's `chromium` package "
                "(apt-get install chromium, or scripts/install-deps.sh) or set CHOKELOOPS_CHROMIUM to a Chrome/Chromium binary");
  fs::path html = fs::absolute(fs::path(outdir) / "view.html");
  {
    // (Re)write the page when it is missing or older than what it shows.
    std::error_code ec;
    bool stale = !fs::exists(html);
    for (const char* input : {"loops.json", "surface.ply"}) {
      fs::path p = fs::path(outdir) / input;
      if (!stale && fs::exists(p) && fs::last_write_time(p, ec) > fs::last_write_time(html, ec)) stale = true;
    }
    if (stale) write_view_html(outdir);
  }
  fs::path target = fs::absolute(png_path);
  if (target.has_parent_path() && !fs::is_directory(target.parent_path()))
    throw Error("cannot write " + png_path + ": no such directory " + target.parent_path().string());

  std::string tmpl = (fs::temp_directory_path() / "chokeloops-chromium-XXXXXX").string();
  if (!::mkdtemp(tmpl.data())) throw Error("cannot create a temporary directory for Chromium", 3);
  fs::path tmp(tmpl);
  struct Cleanup {
    fs::path p;
    ~Cleanup() { std::error_code ec; fs::remove_all(p, ec); }
  } cleanup{tmp};
  fs::path shot = tmp / "shot.png", log = tmp / "chromium.log";

  std::vector<std::string> args = {chromium};
  for (auto& f : chromium_flags(width, height)) args.push_back(f);
  args.push_back("--user-data-dir=" + (tmp / "profile").string());
  args.push_back("--screenshot=" + shot.string());
  args.push_back(url_for(html) + "#render");
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);

  pid_t pid = ::fork();
  if (pid < 0) throw Error("cannot start Chromium (fork failed)", 3);
  if (pid == 0) {
    ::setpgid(0, 0);
    int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    int devnull = ::open("/dev/null", O_RDONLY);
    if (devnull >= 0) ::dup2(devnull, 0);
    if (fd >= 0) { ::dup2(fd, 1); ::dup2(fd, 2); }
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  ::setpgid(pid, pid);
  int status = 0;
  auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(180);
  bool timed_out = false;
  for (;;) {
    pid_t r = ::waitpid(pid, &status, WNOHANG);
    if (r == pid) break;
    if (r < 0 && errno != EINTR) break;
    if (std::chrono::steady_clock::now() > deadline) {
      ::kill(-pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      timed_out = true;
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(40));
  }
  ::kill(-pid, SIGTERM);  // helpers left behind by the browser, if any

  std::error_code ec;
  if (timed_out || !fs::exists(shot) || fs::file_size(shot, ec) == 0) {
    std::string tail;
    {
      std::ifstream in(log);
      std::string line;
      std::vector<std::string> lines;
      while (std::getline(in, line)) lines.push_back(line);
      for (std::size_t i = lines.size() > 8 ? lines.size() - 8 : 0; i < lines.size(); ++i) tail += "\n  " + lines[i];
    }
    throw Error(std::string("Chromium (") + chromium + ") " + (timed_out ? "timed out" : "did not write the picture") +
                " for " + html.string() + (tail.empty() ? "" : "; its last output:" + tail), 3);
  }
  fs::copy_file(shot, target, fs::copy_options::overwrite_existing, ec);
  if (ec) throw Error("cannot write " + target.string() + ": " + ec.message(), 3);
}

}  // namespace chokeloops
