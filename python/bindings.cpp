// The pybind11 module chokeloops._chokeloops: the engine on numpy arrays. The pure-Python package
// (python/chokeloops/__init__.py) wraps it; see there for the documented API.
//
// Conventions: a grid array is indexed a[i, j, k] = value at origin + voxel_size * (i, j, k), i.e. shape
// (nx, ny, nz). The engine stores x fastest, which is numpy's Fortran order: arrays handed out are
// Fortran-ordered views of the engine's own storage (no copy); arrays taken in are copied once into it
// (directly when Fortran-contiguous float32). Results hand out read-only views of the result object's vectors.
// Every computation runs with the GIL released. chokeloops::Error becomes chokeloops.InputError
// (a ValueError, exit code 2) or chokeloops.ResourceError (a MemoryError, exit code 3) with the CLI's message;
// chokeloops::InternalError (a bug) becomes chokeloops.InternalError (a RuntimeError, exit code 4).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <optional>
#include <thread>

#include <tbb/global_control.h>

#include "chokeloops/analyze.h"
#include "chokeloops/batch.h"
#include "chokeloops/output/view.h"

namespace py = pybind11;
using namespace chokeloops;

namespace {

PyObject* g_error = nullptr;           // chokeloops.Error(Exception)
PyObject* g_input_error = nullptr;     // chokeloops.InputError(Error, ValueError)
PyObject* g_resource_error = nullptr;  // chokeloops.ResourceError(Error, MemoryError)
PyObject* g_internal_error = nullptr;  // chokeloops.InternalError(Error, RuntimeError): a bug, CLI exit code 4

[[noreturn]] void input_error(const std::string& msg) { throw Error(msg, 2); }

// ---- options ---------------------------------------------------------------------------------------------

Threshold threshold(py::handle v, const char* name) {
  if (py::isinstance<py::str>(v)) return Threshold::parse(v.cast<std::string>());
  if (py::isinstance<py::float_>(v) || py::isinstance<py::int_>(v)) {
    double x = v.cast<double>();
    if (!std::isfinite(x) || x < 0) input_error(std::string(name) + " must be a non-negative length or a percentage like '10%'");
    return Threshold{x, false};
  }
  throw py::type_error(std::string(name) + " must be a length (float) or a percentage string like '50%'");
}

struct Settings {
  AnalyzeOptions analyze;
  int threads = 0;
  std::array<double, 3> origin{0, 0, 0};
  bool origin_given = false;
  double grid_voxel_size = 0;  // voxel size of an array input (0: 1.0)
};

// Keyword options, named as the CLI's (dmax, min_persistence, side, resolution, voxel_size, margin,
// max_memory, threads, shorten, slide, plane_start, check, fill_holes, iso, grid, origin). Unknown names: TypeError.
Settings settings(const py::dict& kw) {
  Settings s;
  AnalyzeOptions& o = s.analyze;
  for (auto item : kw) {
    const std::string key = py::str(item.first);
    py::handle v = item.second;
    if (v.is_none()) continue;  // the default
    if (key == "resolution") {
      if (py::isinstance<py::str>(v)) {
        if (v.cast<std::string>() != "auto") input_error("resolution must be an integer or 'auto'");
        o.resolution_auto = true;
      } else {
        long r = v.cast<long>();
        if (r < 8 || r > 4096) input_error("resolution must be in [8, 4096], got " + std::to_string(r));
        o.levelset.resolution = int(r);
      }
    } else if (key == "voxel_size") {
      double h = v.cast<double>();
      if (!(h > 0) || !std::isfinite(h)) input_error("voxel_size must be positive");
      o.levelset.voxel_size = h;
      s.grid_voxel_size = h;
    } else if (key == "origin") {
      auto p = v.cast<std::vector<double>>();
      if (p.size() != 3) input_error("origin must have 3 coordinates");
      s.origin = {p[0], p[1], p[2]};
      s.origin_given = true;
    } else if (key == "margin") {
      o.levelset.margin = v.cast<double>();
    } else if (key == "dmax") {
      o.chokes.d_max = threshold(v, "dmax");
    } else if (key == "min_persistence") {
      o.chokes.min_persistence = threshold(v, "min_persistence");
    } else if (key == "side") {
      std::string side = v.cast<std::string>();
      if (side != "handle" && side != "tunnel" && side != "both") input_error("side must be handle, tunnel or both");
      o.chokes.handles = side != "tunnel";
      o.chokes.tunnels = side != "handle";
    } else if (key == "max_memory") {
      if (py::isinstance<py::str>(v)) o.levelset.max_memory = parse_bytes(v.cast<std::string>());
      else o.levelset.max_memory = v.cast<std::size_t>();
    } else if (key == "threads") {
      long t = v.cast<long>();
      if (t < 1) input_error("threads must be a positive integer");
      s.threads = int(t);
    } else if (key == "shorten") o.loops.shorten = v.cast<bool>();
    else if (key == "slide") o.loops.slide = v.cast<bool>();
    else if (key == "plane_start") o.loops.plane_start = v.cast<bool>();
    else if (key == "check") o.check_generators = v.cast<bool>();
    else if (key == "fill_holes") o.levelset.fill_holes = v.cast<bool>();
    else if (key == "iso") o.levelset.iso = v.cast<double>();
    else if (key == "grid") o.levelset.grid_name = v.cast<std::string>();
    else throw py::type_error("unexpected keyword argument '" + key + "'");
  }
  o.levelset.quiet = true;
  return s;
}

std::unique_ptr<tbb::global_control> limit_threads(int n) {
  if (n <= 0) return nullptr;
  return std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, std::size_t(n));
}

// Ctrl-C and the caller's progress callback: the engine asks between stages, and between loops in the loop
// stage, whether to go on; this looks at Python's signals then and hands (stage, fraction) to the callback.
// An exception the callback raises stops the analysis and comes out of analyze() as it was raised.
struct Interrupt {
  bool interrupted = false;
  std::thread::id owner = std::this_thread::get_id();
  py::object callback;                           // None, or callable(stage, fraction)
  std::optional<py::error_already_set> raised;   // what the callback raised
  ProgressFn fn() {
    return [this](const char* stage, double fraction) {
      if (std::this_thread::get_id() != owner) return true;
      py::gil_scoped_acquire gil;
      if (PyErr_CheckSignals() != 0) {
        PyErr_Clear();
        interrupted = true;
        return false;
      }
      if (callback && !callback.is_none()) {
        try {
          callback(stage, fraction);
        } catch (py::error_already_set& e) {
          raised.emplace(std::move(e));
          return false;
        }
      }
      return true;
    };
  }
  // Called with the GIL held, after the computation threw: the callback's exception, or a KeyboardInterrupt,
  // rather than an Error.
  void rethrow_if_interrupted() {
    if (raised) {
      py::error_already_set e = std::move(*raised);
      raised.reset();
      throw e;
    }
    if (!interrupted) return;
    PyErr_SetNone(PyExc_KeyboardInterrupt);
    throw py::error_already_set();
  }
};

// ---- arrays ---------------------------------------------------------------------------------------------

// A numpy view of a vector's storage, kept alive by `owner`.
template <class T>
py::array view(const T* data, std::vector<py::ssize_t> shape, py::handle owner) {
  std::vector<py::ssize_t> strides(shape.size());
  py::ssize_t s = sizeof(T);
  for (std::size_t d = shape.size(); d-- > 0;) {
    strides[d] = s;
    s *= shape[d];
  }
  py::array a(py::dtype::of<T>(), shape, strides, data, owner);
  a.attr("flags").attr("writeable") = false;  // the result's own data: to_json() and write() read it
  return a;
}

// Moves a vector into a capsule and returns an array over it (no copy).
template <class T>
py::array adopt(std::vector<T>&& v, std::vector<py::ssize_t> shape, std::vector<py::ssize_t> strides) {
  auto* heap = new std::vector<T>(std::move(v));
  py::capsule owner(heap, [](void* p) { delete static_cast<std::vector<T>*>(p); });
  return py::array(py::dtype::of<T>(), shape, strides, heap->data(), owner);
}

py::array grid_array(ScalarGrid& grid, py::handle owner) {
  const py::ssize_t f = sizeof(float), nx = grid.dims[0], ny = grid.dims[1], nz = grid.dims[2];
  if (owner) {
    py::array a(py::dtype::of<float>(), {nx, ny, nz}, {f, f * nx, f * nx * ny}, grid.values.data(), owner);
    a.attr("flags").attr("writeable") = false;
    return a;
  }
  return adopt(std::move(grid.values), {nx, ny, nz}, {f, f * nx, f * nx * ny});
}

ScalarGrid grid_from_array(py::handle obj, const Settings& s) {
  auto a = py::array_t<float, py::array::forcecast>::ensure(obj);
  if (!a) {
    PyErr_Clear();
    input_error("the grid must be a numeric array");
  }
  if (a.ndim() != 3) input_error("the grid must be a 3-D array indexed [i, j, k] (got " + std::to_string(a.ndim()) + "-D)");
  ScalarGrid g;
  for (int d = 0; d < 3; ++d) {
    if (a.shape(d) < 2) input_error("the grid must have at least 2 samples along each axis");
    if (a.shape(d) > (1 << 20)) input_error("the grid is too large along an axis");
    g.dims[d] = int(a.shape(d));
  }
  g.voxel_size = s.grid_voxel_size > 0 ? s.grid_voxel_size : 1.0;
  g.origin = s.origin;
  const std::size_t n = std::size_t(g.vertex_count());
  g.values.resize(n);
  if (a.flags() & py::array::f_style) {
    std::memcpy(g.values.data(), a.data(), n * sizeof(float));
  } else {
    auto r = a.unchecked<3>();
    py::gil_scoped_release release;
    for (int k = 0; k < g.dims[2]; ++k)
      for (int j = 0; j < g.dims[1]; ++j)
        for (int i = 0; i < g.dims[0]; ++i) g.values[std::size_t(g.index(i, j, k))] = r(i, j, k);
  }
  for (float v : g.values)
    if (!std::isfinite(v)) input_error("the grid holds a NaN or infinite value");
  return g;
}

TriangleMesh mesh_from_arrays(py::handle vobj, py::handle fobj) {
  auto V = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(vobj);
  auto F = py::array_t<long long, py::array::c_style | py::array::forcecast>::ensure(fobj);
  if (!V || !F) PyErr_Clear();
  if (!V || V.ndim() != 2 || V.shape(1) != 3) input_error("mesh vertices must be an (n, 3) array");
  if (!F || F.ndim() != 2 || F.shape(1) != 3) input_error("mesh faces must be an (m, 3) integer array of vertex indices");
  if (V.shape(0) < 3 || F.shape(0) < 1) input_error("the mesh has no faces");
  TriangleMesh m;
  m.vertices.resize(std::size_t(V.shape(0)));
  std::memcpy(m.vertices.data(), V.data(), m.vertices.size() * sizeof(m.vertices[0]));
  for (auto& p : m.vertices)
    for (double c : p)
      if (!std::isfinite(c) || std::abs(c) > 1e30) input_error("mesh vertices hold a NaN, infinite or huge coordinate");
  const long long nv = V.shape(0);
  auto f = F.unchecked<2>();
  m.faces.resize(std::size_t(F.shape(0)));
  for (py::ssize_t i = 0; i < F.shape(0); ++i)
    for (int c = 0; c < 3; ++c) {
      long long idx = f(i, c);
      if (idx < 0 || idx >= nv)
        input_error("face " + std::to_string(i) + " refers to vertex " + std::to_string(idx) + " of " + std::to_string(nv));
      m.faces[std::size_t(i)][c] = int(idx);
    }
  return m;
}

enum class SourceKind { Path, Mesh, Grid };

SourceKind source_kind(py::handle src) {
  if (py::isinstance<py::str>(src) || py::hasattr(src, "__fspath__")) return SourceKind::Path;
  if (py::isinstance<py::array>(src)) return SourceKind::Grid;
  if ((py::isinstance<py::tuple>(src) || py::isinstance<py::list>(src)) && py::len(src) == 2) return SourceKind::Mesh;
  throw py::type_error("source must be a path, a (V, F) pair of arrays or a 3-D signed distance array");
}

std::string path_of(py::handle src) { return py::module_::import("os").attr("fspath")(src).cast<std::string>(); }

// ---- analyze ---------------------------------------------------------------------------------------------

struct Result {
  AnalyzeResult r;
  AnalyzeOptions options;
};

// A mesh given as arrays: the file path's pipeline from mesh_to_levelset on (analyze.h does the same for
// files, plus the auto resolution search and the coarse-grid hint, which need the file).
AnalyzeResult analyze_mesh(const TriangleMesh& mesh, const AnalyzeOptions& options, const ProgressFn& progress) {
  if (options.resolution_auto) input_error("resolution='auto' needs a mesh file; give a number for arrays");
  auto t = std::chrono::steady_clock::now();
  LevelSetResult ls = mesh_to_levelset(mesh, options.levelset, "mesh");
  double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
  ScalarGrid grid = std::move(ls.grid);
  AnalyzeResult r = analyze_grid(std::move(grid), options, progress, "mesh");
  r.resolution = options.levelset.voxel_size > 0 ? 0 : options.levelset.resolution;
  if (ls.report.closed) r.input_genus = ls.report.genus;
  std::vector<std::string> warnings = ls.warnings;
  if (r.input_genus >= 0 && r.surface_stats.genus != r.input_genus)
    warnings.push_back("the grid is too coarse: the input mesh has genus " + std::to_string(r.input_genus) +
                       " but its surface at this resolution has genus " + std::to_string(r.surface_stats.genus) +
                       "; rerun with a finer resolution");
  warnings.insert(warnings.end(), r.warnings.begin(), r.warnings.end());
  r.warnings = warnings;
  r.levelset_info = std::move(ls);
  r.levelset_info.grid = ScalarGrid{};
  r.timings_ms["levelset"] = ms;
  r.timings_ms["total"] += ms;
  return r;
}

std::shared_ptr<Result> py_analyze(py::handle src, py::kwargs kw) {
  // progress: analyze()'s own keyword (the other functions have no stages to report).
  py::object progress = py::none();
  if (kw.contains("progress")) {
    progress = kw["progress"];
    PyDict_DelItemString(kw.ptr(), "progress");
    if (!progress.is_none() && !PyCallable_Check(progress.ptr()))
      throw py::type_error("progress must be a callable taking (stage, fraction)");
  }
  Settings s = settings(kw);
  auto out = std::make_shared<Result>();
  out->options = s.analyze;
  Interrupt interrupt;
  interrupt.callback = progress;
  SourceKind kind = source_kind(src);
  try {
    if (kind == SourceKind::Path) {
      std::string path = path_of(src);
      py::gil_scoped_release release;
      auto limit = limit_threads(s.threads);
      out->r = analyze(path, s.analyze, interrupt.fn());
    } else if (kind == SourceKind::Mesh) {
      py::sequence seq = py::reinterpret_borrow<py::sequence>(src);
      TriangleMesh mesh = mesh_from_arrays(seq[0], seq[1]);
      py::gil_scoped_release release;
      auto limit = limit_threads(s.threads);
      out->r = analyze_mesh(mesh, s.analyze, interrupt.fn());
    } else {
      ScalarGrid grid = grid_from_array(src, s);
      py::gil_scoped_release release;
      auto limit = limit_threads(s.threads);
      out->r = analyze_grid(std::move(grid), s.analyze, interrupt.fn(), "array");
    }
  } catch (const Error&) {
    interrupt.rethrow_if_interrupted();
    throw;
  }
  return out;
}

py::array vec3(const std::array<double, 3>& p) {
  py::array_t<double> a(3);
  std::copy(p.begin(), p.end(), a.mutable_data());
  return std::move(a);
}

py::list loops_of(py::object self) {
  Result& res = self.cast<Result&>();
  py::list out;
  const AnalyzeResult& r = res.r;
  for (std::size_t i = 0; i < r.loops.size(); ++i) {
    const Loop& l = r.loops[i];
    const Choke& c = l.choke;
    py::dict d;
    d["id"] = i;
    d["side"] = to_string(c.side);
    d["kind"] = to_string(c.kind);
    d["depth"] = c.depth;
    d["persistence"] = c.persistence;
    d["birth"] = c.birth;
    d["death"] = c.death;
    d["length"] = l.length;
    d["raw_length"] = l.raw_length;
    d["choke_point"] = vec3(c.point);
    d["centroid"] = vec3(l.centroid);
    d["normal"] = vec3(l.normal);
    d["radius_min"] = l.radius_min;
    d["radius_mean"] = l.radius_mean;
    d["found"] = l.found;
    d["note"] = l.note;
    d["points"] = view(l.points.empty() ? nullptr : l.points[0].data(), {py::ssize_t(l.points.size()), 3}, self);
    d["edge_path"] = view(l.edge_path.data(), {py::ssize_t(l.edge_path.size())}, self);
    out.append(d);
  }
  return out;
}

py::array diagram_array(const PersistenceDiagram& dg) {
  std::vector<double> rows;
  rows.reserve(3 * (dg.pairs.size() + dg.essential.size()));
  for (const auto* list : {&dg.pairs, &dg.essential})
    for (auto& p : *list) {
      rows.push_back(p.dim);
      rows.push_back(p.birth);
      rows.push_back(p.essential() ? std::numeric_limits<double>::infinity() : double(p.death));
    }
  const py::ssize_t n = py::ssize_t(rows.size() / 3);
  return adopt(std::move(rows), {n, 3}, {3 * py::ssize_t(sizeof(double)), py::ssize_t(sizeof(double))});
}

// ---- batch -----------------------------------------------------------------------------------------------

py::object or_none(bool ok, py::object v) { return ok ? v : py::none(); }

py::dict item_dict(const BatchItem& it) {
  const bool ok = it.status == "ok";
  py::dict d;
  d["input"] = it.input;
  d["status"] = it.status;
  d["outdir"] = it.outdir;
  d["genus"] = or_none(ok, py::int_(it.genus));
  d["handle_generators"] = or_none(ok, py::int_(it.handle_generators));
  d["tunnel_generators"] = or_none(ok, py::int_(it.tunnel_generators));
  d["handle_chokes"] = or_none(ok, py::int_(it.handle_chokes));
  d["tunnel_chokes"] = or_none(ok, py::int_(it.tunnel_chokes));
  const bool deep = it.deepest_loop >= 0, pers = it.most_persistent_loop >= 0;
  d["deepest_loop"] = or_none(deep, py::int_(it.deepest_loop));
  d["deepest_side"] = or_none(deep, py::str(it.deepest_side));
  d["deepest_depth"] = or_none(deep, py::float_(it.deepest_depth));
  d["most_persistent_loop"] = or_none(pers, py::int_(it.most_persistent_loop));
  d["most_persistent_side"] = or_none(pers, py::str(it.most_persistent_side));
  d["most_persistent"] = or_none(pers, py::float_(it.most_persistent));
  d["seconds"] = it.seconds;
  d["resumed"] = it.resumed;
  d["exit_code"] = it.exit_code;
  d["error"] = it.error;
  return d;
}

BatchItem item_from_dict(const py::dict& d) {
  BatchItem it;
  auto str = [&](const char* k) { return d.contains(k) && !d[k].is_none() ? py::str(d[k]).cast<std::string>() : std::string(); };
  auto num = [&](const char* k, double dflt) { return d.contains(k) && !d[k].is_none() ? d[k].cast<double>() : dflt; };
  it.input = str("input");
  it.status = str("status");
  it.outdir = str("outdir");
  it.genus = int(num("genus", -1));
  it.handle_generators = int(num("handle_generators", 0));
  it.tunnel_generators = int(num("tunnel_generators", 0));
  it.handle_chokes = int(num("handle_chokes", 0));
  it.tunnel_chokes = int(num("tunnel_chokes", 0));
  it.deepest_loop = int(num("deepest_loop", -1));
  it.deepest_side = str("deepest_side");
  it.deepest_depth = num("deepest_depth", 0);
  it.most_persistent_loop = int(num("most_persistent_loop", -1));
  it.most_persistent_side = str("most_persistent_side");
  it.most_persistent = num("most_persistent", 0);
  it.seconds = num("seconds", 0);
  it.resumed = d.contains("resumed") && d["resumed"].cast<bool>();
  it.exit_code = int(num("exit_code", 0));
  it.error = str("error");
  return it;
}

}  // namespace

PYBIND11_MODULE(_chokeloops, m) {
  m.doc() = "chokeloops engine (see the chokeloops package for the documented API)";
  m.attr("__version__") = CHOKELOOPS_VERSION;

  g_error = PyErr_NewExceptionWithDoc("chokeloops.Error", "Any error the engine reports (the CLI's message).",
                                      PyExc_Exception, nullptr);
  py::tuple input_bases = py::make_tuple(py::handle(g_error), py::handle(PyExc_ValueError));
  g_input_error = PyErr_NewExceptionWithDoc("chokeloops.InputError",
                                            "Bad input or parameters (CLI exit code 2).", input_bases.ptr(), nullptr);
  py::tuple resource_bases = py::make_tuple(py::handle(g_error), py::handle(PyExc_MemoryError));
  g_resource_error = PyErr_NewExceptionWithDoc("chokeloops.ResourceError",
                                               "Out of memory or another resource (CLI exit code 3); the message names a resolution that fits.",
                                               resource_bases.ptr(), nullptr);
  py::tuple internal_bases = py::make_tuple(py::handle(g_error), py::handle(PyExc_RuntimeError));
  g_internal_error = PyErr_NewExceptionWithDoc("chokeloops.InternalError",
                                               "A failed internal self-check: a bug in chokeloops, not a problem with the input (CLI exit code 4).",
                                               internal_bases.ptr(), nullptr);
  m.attr("Error") = py::handle(g_error);
  m.attr("InternalError") = py::handle(g_internal_error);
  m.attr("InputError") = py::handle(g_input_error);
  m.attr("ResourceError") = py::handle(g_resource_error);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const Error& e) {
      PyErr_SetString(e.exit_code == 3 ? g_resource_error : e.exit_code == 2 ? g_input_error : g_error, e.what());
    } catch (const InternalError& e) {
      PyErr_SetString(g_internal_error,
                      (std::string("internal error (a bug in chokeloops, not a problem with the input): ") + e.what() +
                       "; please report it with the input and the call").c_str());
    } catch (const std::bad_alloc&) {
      PyErr_SetString(g_resource_error, "out of memory; use a coarser resolution");
    }
  });

  py::class_<Result, std::shared_ptr<Result>>(m, "Result", "What analyze() found; arrays are views of it.")
      .def_property_readonly("input", [](const Result& r) { return r.r.input; })
      .def_property_readonly("loops", [](py::object self) { return loops_of(self); },
                             "list of dicts, the fields of loops.json; points an (n, 3) array")
      .def_property_readonly("surface", [](py::object self) {
            Result& r = self.cast<Result&>();
            auto& s = r.r.surface;
            return py::make_tuple(view(s.vertices.empty() ? nullptr : s.vertices[0].data(), {py::ssize_t(s.vertices.size()), 3}, self),
                                  view(s.faces.empty() ? nullptr : s.faces[0].data(), {py::ssize_t(s.faces.size()), 3}, self));
          }, "(V, F): the zero level set, float64 (n, 3) and int32 (m, 3)")
      .def_property_readonly("diagram", [](const Result& r) { return diagram_array(r.r.diagram); },
                             "(n, 3) array of (dim, birth, death) of the signed distance's lower-star filtration; inf = essential")
      .def_property_readonly("handle_diagram", [](py::object self) {
            auto& v = self.cast<Result&>().r.chokes.handle_diagram;
            return view(v.empty() ? nullptr : v[0].data(), {py::ssize_t(v.size()), 2}, self);
          }, "(n, 2) array of (depth, persistence) of every handle candidate")
      .def_property_readonly("tunnel_diagram", [](py::object self) {
            auto& v = self.cast<Result&>().r.chokes.tunnel_diagram;
            return view(v.empty() ? nullptr : v[0].data(), {py::ssize_t(v.size()), 2}, self);
          }, "(n, 2) array of (depth, persistence) of every tunnel candidate")
      .def_property_readonly("sdf", [](py::object self) { return grid_array(self.cast<Result&>().r.grid, self); },
                             "the signed distance grid analysed, (nx, ny, nz) float32 view")
      .def_property_readonly("origin", [](const Result& r) { return r.r.grid.origin; })
      .def_property_readonly("voxel_size", [](const Result& r) { return r.r.grid.voxel_size; })
      .def_property_readonly("warnings", [](const Result& r) { return r.r.warnings; })
      .def_property_readonly("genus", [](const Result& r) { return r.r.surface_stats.genus; })
      .def_property_readonly("input_genus", [](const Result& r) { return r.r.input_genus; })
      .def_property_readonly("components", [](const Result& r) { return r.r.surface_stats.components; })
      .def_property_readonly("closed", [](const Result& r) { return r.r.surface_stats.closed_manifold; })
      .def_property_readonly("R_in", [](const Result& r) { return r.r.chokes.R_in; })
      .def_property_readonly("R_out", [](const Result& r) { return r.r.chokes.R_out; })
      .def_property_readonly("timings_ms", [](const Result& r) { return r.r.timings_ms; })
      .def("to_json", [](const Result& r) { return report_json(r.r, r.options); }, "the text of loops.json")
      .def("write", [](const Result& r, const std::string& outdir, bool view_html) {
            py::gil_scoped_release release;
            write_report(r.r, r.options, outdir);
            if (view_html) write_view_html(outdir);
          }, py::arg("outdir"), py::arg("view") = true,
          "writes surface.ply, loops.ply, loops.obj, loops.json (and view.html) into outdir");

  m.def("analyze", &py_analyze, py::arg("source"));

  m.def("levelset", [](py::handle src, py::kwargs kw) {
    Settings s = settings(kw);
    LevelSetResult ls;
    if (source_kind(src) == SourceKind::Path) {
      std::string path = path_of(src);
      py::gil_scoped_release release;
      auto limit = limit_threads(s.threads);
      ls = make_levelset(path, s.analyze.levelset);
    } else if (source_kind(src) == SourceKind::Mesh) {
      py::sequence seq = py::reinterpret_borrow<py::sequence>(src);
      TriangleMesh mesh = mesh_from_arrays(seq[0], seq[1]);
      py::gil_scoped_release release;
      auto limit = limit_threads(s.threads);
      ls = mesh_to_levelset(mesh, s.analyze.levelset, "mesh");
    } else {
      throw py::type_error("levelset() takes a path or a (V, F) pair of arrays");
    }
    auto origin = ls.grid.origin;
    double h = ls.grid.voxel_size;
    py::array a = grid_array(ls.grid, py::handle());
    return py::make_tuple(a, origin, h, ls.warnings);
  }, py::arg("source"));

  m.def("persistence", [](py::handle array, py::kwargs kw) {
    Settings s = settings(kw);
    ScalarGrid g = grid_from_array(array, s);
    PersistenceDiagram dg;
    {
      py::gil_scoped_release release;
      auto limit = limit_threads(s.threads);
      dg = lower_star_persistence(g);
    }
    return diagram_array(dg);
  }, py::arg("array"));

  // Batch pieces; the loop over inputs (locally or on Dask workers) is chokeloops.batch in Python.
  m.def("batch_item_dirs", &batch_item_dirs, py::arg("inputs"), py::arg("outdir"));
  m.def("options_key", [](py::kwargs kw) { return options_key(settings(kw).analyze); });
  m.def("read_finished_item", [](const std::string& dir, const std::string& key) -> py::object {
    BatchItem it;
    if (!read_finished_item(dir, key, it)) return py::none();
    return item_dict(it);
  }, py::arg("item_dir"), py::arg("key"));
  m.def("analyze_item", [](const std::string& input, const std::string& dir, bool resume, bool view_html, py::kwargs kw) {
    Settings s = settings(kw);
    BatchOptions bo;
    bo.analyze = s.analyze;
    bo.threads = s.threads;
    bo.resume = resume;
    bo.view = view_html;
    BatchItem it;
    {
      py::gil_scoped_release release;
      it = analyze_item(input, dir, bo);
    }
    return item_dict(it);
  }, py::arg("input"), py::arg("item_dir"), py::arg("resume") = true, py::arg("view") = true);
  m.def("write_batch_summary", [](const py::list& items, const std::string& path) {
    std::vector<BatchItem> v;
    for (auto d : items) v.push_back(item_from_dict(d.cast<py::dict>()));
    write_batch_summary(v, path);
  }, py::arg("items"), py::arg("path"));
  m.def("batch_columns", &batch_columns);
}
