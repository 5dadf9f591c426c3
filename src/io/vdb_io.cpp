// OpenVDB file IO and FloatGrid <-> ScalarGrid conversions (stage `levelset`, see DESIGN.md §4).
#include "chokeloops/io/vdb_io.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>

#include <openvdb/io/File.h>
#include <openvdb/tools/Dense.h>

#include "common/first_non_finite.h"
#include "vdb_guard.h"

namespace chokeloops {
namespace {

std::size_t physical_memory() {
  std::ifstream in("/proc/meminfo");
  std::string key;
  std::size_t kb = 0;
  std::string unit;
  while (in >> key >> kb >> unit) {
    if (key == "MemTotal:") return kb * 1024;
  }
  return std::size_t(8) << 30;
}

std::string quoted(const std::string& path) { return "'" + path + "'"; }

void check_readable(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (path.empty()) throw Error("empty input file name");
  if (!fs::exists(path, ec)) throw Error(quoted(path) + ": no such file");
  if (fs::is_directory(path, ec)) throw Error(quoted(path) + ": is a directory, not a .vdb file");
  std::ifstream probe(path, std::ios::binary);
  if (!probe) throw Error(quoted(path) + ": cannot open for reading (permission denied?)");
  probe.seekg(0, std::ios::end);
  if (probe.tellg() <= 0) throw Error(quoted(path) + ": empty file, not a VDB file");
}

std::string one_line(std::string s) {
  for (auto& c : s)
    if (c == '\n' || c == '\r') c = ' ';
  return s;
}

// Why OpenVDB failed, for the message. The guard (vdb_guard.cpp) makes the file's stream throw when a read fails;
// libstdc++'s message for that says only "basic_ios::clear: iostream error", so it is named for what it means.
std::string reason(const std::exception& e) {
  const std::string what = e.what();
  if (what.rfind("basic_ios::clear", 0) == 0) return "the file ends inside its data";
  return one_line(what);
}

// Opens the file (no delayed loading: the grid must not depend on the file staying unchanged). Every value
// block is then read through the guard of vdb_guard.cpp, which refuses a corrupt one before OpenVDB's buffers.
std::unique_ptr<openvdb::io::File> open_vdb(const std::string& path) {
  ensure_openvdb_initialized();
  check_readable(path);
  require_vdb_guard(path);
  auto file = std::make_unique<openvdb::io::File>(path);
  try {
    file->open(/*delayLoad=*/false);
  } catch (const openvdb::Exception& e) {
    throw Error(quoted(path) + ": not a readable VDB file (" + one_line(e.what()) + ")");
  } catch (const std::exception& e) {
    throw Error(quoted(path) + ": not a readable VDB file (" + reason(e) + ")");
  }
  return file;
}

std::string describe(const std::vector<VdbGridInfo>& grids) {
  if (grids.empty()) return "it holds no grids";
  std::ostringstream s;
  s << "it holds ";
  for (std::size_t i = 0; i < grids.size(); ++i) {
    if (i) s << ", ";
    s << "'" << grids[i].name << "' (" << grids[i].type << ")";
  }
  return s.str();
}

std::vector<VdbGridInfo> list_open(openvdb::io::File& file, const std::string& path) {
  std::vector<VdbGridInfo> out;
  try {
    auto metas = file.readAllGridMetadata();
    for (auto& g : *metas) {
      if (!g) continue;
      out.push_back({g->getName(), g->valueType(), openvdb::GridBase::gridClassToString(g->getGridClass())});
    }
  } catch (const openvdb::Exception& e) {
    throw Error(quoted(path) + ": corrupt VDB file (" + one_line(e.what()) + ")");
  } catch (const std::exception& e) {
    throw Error(quoted(path) + ": corrupt VDB file (" + reason(e) + ")");
  }
  return out;
}

struct AxisTransform {
  double h;
  openvdb::Vec3d offset;  // world position of index (0,0,0)
};

AxisTransform axis_transform(const openvdb::math::Transform& xf, const std::string& what) {
  if (!xf.isLinear()) throw Error(what + ": non-linear (frustum) transform is not supported");
  const openvdb::Vec3d o = xf.indexToWorld(openvdb::Vec3d(0, 0, 0));
  const openvdb::Vec3d ex = xf.indexToWorld(openvdb::Vec3d(1, 0, 0)) - o;
  const openvdb::Vec3d ey = xf.indexToWorld(openvdb::Vec3d(0, 1, 0)) - o;
  const openvdb::Vec3d ez = xf.indexToWorld(openvdb::Vec3d(0, 0, 1)) - o;
  const double h = ex[0];
  const double tol = 1e-6 * std::abs(h);
  auto near = [&](double a, double b) { return std::abs(a - b) <= tol; };
  if (!(h > 0) || !std::isfinite(h) || !near(ex[1], 0) || !near(ex[2], 0) || !near(ey[0], 0) || !near(ey[1], h) ||
      !near(ey[2], 0) || !near(ez[0], 0) || !near(ez[1], 0) || !near(ez[2], h)) {
    std::ostringstream s;
    s << what << ": transform must be a uniform positive scale plus translation (voxel size " << xf.voxelSize()
      << "); resample the grid first";
    throw Error(s.str());
  }
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(o[a])) throw Error(what + ": transform has a non-finite translation");
  return {h, o};
}

}  // namespace

void ensure_openvdb_initialized() {
  static std::once_flag flag;
  std::call_once(flag, [] { openvdb::initialize(); });
}

std::vector<VdbGridInfo> list_vdb_grids(const std::string& path) {
  auto file = open_vdb(path);
  auto out = list_open(*file, path);
  file->close();
  return out;
}

openvdb::FloatGrid::Ptr read_vdb_float_grid(const std::string& path, const std::string& grid_name) {
  VdbRootCheck root_check;  // the float grid's root node is checked before OpenVDB reads it
  auto file = open_vdb(path);
  auto grids = list_open(*file, path);
  std::string chosen;
  bool found = false;
  for (auto& g : grids) {
    if (!grid_name.empty() && g.name != grid_name) continue;
    if (g.type == "float") {
      chosen = g.name;
      found = true;
      break;
    }
    if (!grid_name.empty())
      throw Error(quoted(path) + ": grid '" + grid_name + "' holds " + g.type + " values, not float");
  }
  if (!found) {
    if (!grid_name.empty()) throw Error(quoted(path) + ": no grid named '" + grid_name + "'; " + describe(grids));
    throw Error(quoted(path) + ": no float grid; " + describe(grids));
  }
  openvdb::GridBase::Ptr base;
  try {
    base = file->readGrid(chosen);
  } catch (const openvdb::Exception& e) {
    throw Error(quoted(path) + ": cannot read grid '" + chosen + "' (" + one_line(e.what()) + ")");
  } catch (const std::exception& e) {
    throw Error(quoted(path) + ": cannot read grid '" + chosen + "' (" + reason(e) + ")");
  }
  file->close();
  auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(base);
  if (!grid) throw Error(quoted(path) + ": grid '" + chosen + "' is not a float grid");
  if (grid->activeVoxelCount() == 0)
    throw Error(quoted(path) + ": float grid '" + chosen + "' is empty (no active voxels)");
  return grid;
}

ScalarGrid dense_from_grid(const openvdb::FloatGrid& grid, const openvdb::CoordBBox& bbox, const std::string& what) {
  if (bbox.empty()) throw Error(what + ": empty bounding box");
  const AxisTransform xf = axis_transform(grid.transform(), what);
  const openvdb::Coord d = bbox.dim();
  const std::int64_t n = std::int64_t(d[0]) * d[1] * d[2];
  const std::size_t bytes = std::size_t(n) * sizeof(float);
  const std::size_t limit = physical_memory() / 10 * 8;
  if (bytes > limit) {
    std::ostringstream s;
    s << what << ": dense box " << d[0] << "x" << d[1] << "x" << d[2] << " needs " << (bytes >> 20)
      << " MiB, more than 80% of physical memory (" << (limit >> 20) << " MiB); resample it coarser";
    throw Error(s.str(), 3);
  }
  ScalarGrid out;
  out.dims = {d[0], d[1], d[2]};
  out.voxel_size = xf.h;
  const openvdb::Vec3d o = grid.transform().indexToWorld(bbox.min());
  out.origin = {o[0], o[1], o[2]};
  out.values.resize(std::size_t(n));
  openvdb::tools::Dense<float, openvdb::tools::LayoutXYZ> dense(bbox, out.values.data());
  openvdb::tools::copyToDense(grid, dense);
  return out;
}

ScalarGrid read_vdb_dense(const std::string& path, const std::string& grid_name) {
  auto grid = read_vdb_float_grid(path, grid_name);
  const std::string what = quoted(path) + " grid '" + grid->getName() + "'";
  ScalarGrid out = dense_from_grid(*grid, grid->evalActiveVoxelBoundingBox(), what);
  if (detail::first_non_finite(out.values.data(), out.values.size()) < out.values.size())
    throw Error(what + ": holds non-finite values (NaN or infinity)");
  return out;
}

openvdb::FloatGrid::Ptr grid_from_dense(const ScalarGrid& grid, bool level_set, float background) {
  ensure_openvdb_initialized();
  if (grid.dims[0] < 1 || grid.dims[1] < 1 || grid.dims[2] < 1 ||
      std::int64_t(grid.values.size()) != grid.vertex_count())
    throw Error("cannot convert grid: dims do not match its value count");
  if (!(grid.voxel_size > 0) || !std::isfinite(grid.voxel_size)) throw Error("cannot convert grid: bad voxel size");
  float maxabs = 0;
  bool finite = true;
  for (float v : grid.values) {
    if (!std::isfinite(v)) { finite = false; break; }
    maxabs = std::max(maxabs, std::abs(v));
  }
  if (!finite) throw Error("cannot convert grid: it holds non-finite values");
  float bg = background > 0 ? background : maxabs + float(grid.voxel_size);
  if (!(bg > maxabs)) bg = std::nextafter(maxabs, std::numeric_limits<float>::max());
  auto out = openvdb::FloatGrid::create(bg);
  auto xf = openvdb::math::Transform::createLinearTransform(grid.voxel_size);
  xf->postTranslate(openvdb::Vec3d(grid.origin[0], grid.origin[1], grid.origin[2]));
  out->setTransform(xf);
  const openvdb::CoordBBox bbox(openvdb::Coord(0, 0, 0),
                                openvdb::Coord(grid.dims[0] - 1, grid.dims[1] - 1, grid.dims[2] - 1));
  openvdb::tools::Dense<const float, openvdb::tools::LayoutXYZ> dense(bbox, grid.values.data());
  openvdb::tools::copyFromDense(dense, *out, /*tolerance=*/0.f);
  out->setGridClass(level_set ? openvdb::GRID_LEVEL_SET : openvdb::GRID_FOG_VOLUME);
  return out;
}

void write_vdb(const ScalarGrid& grid, const std::string& path, const std::string& grid_name, bool level_set) {
  auto g = grid_from_dense(grid, level_set);
  g->setName(grid_name);
  try {
    openvdb::io::File file(path);
    file.write({g});
    file.close();
  } catch (const openvdb::Exception& e) {
    throw Error("cannot write '" + path + "': " + one_line(e.what()));
  } catch (const std::exception& e) {
    throw Error("cannot write '" + path + "': " + one_line(e.what()));
  }
}

}  // namespace chokeloops
