// A guard in front of OpenVDB's value-block reader, so that a corrupt .vdb file is refused, never read past a
// buffer.
//
// Why: every block of values in a .vdb file (the voxels of each leaf, and in the topology the tile values of each
// internal node) is stored as an 8-byte length and then that many bytes: blosc or zlib compressed when the length
// is positive, raw when it is zero or negative (minus the byte count). OpenVDB reads a block with
// io::bloscFromStream or io::unzipFromStream (io/Compression.cc), handing it a buffer sized for the values the
// tree expects. OpenVDB 10 (Debian 12 ships 10.0.1) reads a raw block into that buffer for as many bytes as the
// file claims and only then compares the two sizes: one changed byte in a length overflows the heap (libFuzzer
// on bunny_8.vdb: ASan heap-buffer-overflow in bloscFromStream under LeafNode::readBuffers). It also allocates
// whatever positive length the file claims, and hands blosc a header it never compares with that length, which
// lets blosc read past the block. OpenVDB 11 compares the raw length first; the rest it still trusts.
//
// How: both readers are exported by libopenvdb.so and called through its procedure linkage table, so the
// definitions at the end of this file, linked into the program, take their place for every call the library
// makes (ELF symbol interposition, the mechanism that lets a program bring its own malloc). They read the same
// format, but check each block before anything is written: a raw block must be exactly the buffer's size; a
// compressed one no longer than the largest the writer makes for that size (blosc: size + its 16-byte header;
// zlib: compressBound), present in full in the file, and for blosc its header must agree with both sizes
// (blosc_cbuffer_validate) before it is decompressed. A block that fails is an openvdb::IoError, which the
// reader turns into a one-line Error naming the file (exit code 2). A valid file reads exactly as before.
// Metadata, and the names OpenVDB reads with it, are guarded the same way (read_meta_map, check_names below).
// Whether interposition took effect depends on how the program was linked and loaded, so require_vdb_guard()
// proves it once per process: it writes a one-leaf grid with blosc and with zlib into memory, reads it back and
// checks that these functions read its metadata, topology and blocks and that the values came back.
#include "vdb_guard.h"

#include <blosc.h>
#include <dlfcn.h>
#include <zlib.h>

#include <algorithm>
#include <atomic>
#include <cstring>
#include <cstdint>
#include <limits>
#include <memory>
#include <mutex>
#include <sstream>
#include <vector>

#include <openvdb/Exceptions.h>
#include <openvdb/Metadata.h>
#include <openvdb/MetaMap.h>
#include <openvdb/io/Compression.h>
#include <openvdb/io/DelayedLoadMetadata.h>
#include <openvdb/io/GridDescriptor.h>
#include <openvdb/math/Transform.h>
#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>

#include "chokeloops/grid.h"
#include "chokeloops/io/vdb_io.h"

// The topology of float trees. OpenVDB 10's RootNode::readTopology allocates each child (an internal node of
// 32^3 entries) and inserts it into the root's table only after that child's readTopology returns: when the stream
// throws inside it (the file ends, or a value block is refused above), the child and everything it has allocated
// so far are lost (hundreds of KB per refused file; ASan's leak check on fuzz/corpus/vdb/regression-* shows them
// under RootNode::readTopology). The child cannot simply be deleted either: its child mask is read before its
// children, and the entries of children not yet read hold the background value, not a pointer, so OpenVDB's
// destructor would free garbage. InternalNode<...,5>::readTopology is exported and called through the library's
// linkage table, so the definitions below (explicit specialisations, defined before any use in this file) take its
// place, and that of the level-4 node below it: the same format, read the same way, but when a read throws, every
// child not made yet is turned into a tile of the background value (its child-mask bit off), so the node is whole
// again; the level-5 node, which its caller would lose, then deletes itself before the exception goes on.
namespace chokeloops {
namespace {
std::atomic<unsigned long> g_topologies{0};
std::atomic<unsigned long> g_freed{0};
}  // namespace
}  // namespace chokeloops

// The body of both specialisations (they need the node's own members).
#define CHOKELOOPS_READ_INTERNAL_TOPOLOGY(free_self_on_error)                                                       \
  chokeloops::g_topologies.fetch_add(1, std::memory_order_relaxed);                                                \
  const ValueType background = !io::getGridBackgroundValuePtr(is)                                                  \
                                   ? zeroVal<ValueType>()                                                          \
                                   : *static_cast<const ValueType*>(io::getGridBackgroundValuePtr(is));            \
  Index made = 0; /* child-mask positions below this hold a child made here, or a value */                         \
  try {                                                                                                            \
    mChildMask.load(is);                                                                                           \
    mValueMask.load(is);                                                                                           \
    if (io::getFormatVersion(is) < OPENVDB_FILE_VERSION_INTERNALNODE_COMPRESSION) {                                \
      for (Index i = 0; i < NUM_VALUES; ++i) {                                                                     \
        if (this->isChildMaskOn(i)) {                                                                              \
          ChildNodeType* child = new ChildNodeType(PartialCreate(), offsetToGlobalCoord(i), background);           \
          mNodes[i].setChild(child);                                                                               \
          made = i + 1;                                                                                            \
          child->readTopology(is);                                                                                 \
        } else {                                                                                                   \
          ValueType value;                                                                                         \
          is.read(reinterpret_cast<char*>(&value), sizeof(ValueType));                                             \
          mNodes[i].setValue(value);                                                                               \
        }                                                                                                          \
      }                                                                                                            \
    } else {                                                                                                       \
      const bool oldVersion = io::getFormatVersion(is) < OPENVDB_FILE_VERSION_NODE_MASK_COMPRESSION;              \
      const Index numValues = oldVersion ? mChildMask.countOff() : NUM_VALUES;                                     \
      {                                                                                                            \
        std::unique_ptr<ValueType[]> valuePtr(new ValueType[numValues]);                                           \
        ValueType* values = valuePtr.get();                                                                        \
        io::readCompressedValues(is, values, numValues, mValueMask, fromHalf);                                     \
        Index n = 0;                                                                                               \
        for (ValueAllIter iter = this->beginValueAll(); iter; ++iter)                                              \
          mNodes[iter.pos()].setValue(values[oldVersion ? n++ : iter.pos()]);                                      \
      }                                                                                                            \
      for (ChildOnIter iter = this->beginChildOn(); iter; ++iter) {                                                \
        ChildNodeType* child = new ChildNodeType(PartialCreate(), iter.getCoord(), background);                    \
        mNodes[iter.pos()].setChild(child);                                                                        \
        made = iter.pos() + 1;                                                                                     \
        child->readTopology(is, fromHalf);                                                                         \
      }                                                                                                            \
    }                                                                                                              \
  } catch (...) {                                                                                                  \
    for (Index i = made; i < NUM_VALUES; ++i)                                                                      \
      if (mChildMask.isOn(i)) {                                                                                    \
        mChildMask.setOff(i);                                                                                      \
        mNodes[i].setValue(background);                                                                            \
      }                                                                                                            \
    if (free_self_on_error) {                                                                                      \
      chokeloops::g_freed.fetch_add(1, std::memory_order_relaxed);                                                 \
      delete this;                                                                                                 \
    }                                                                                                              \
    throw;                                                                                                         \
  }

namespace openvdb {
OPENVDB_USE_VERSION_NAMESPACE
namespace OPENVDB_VERSION_NAME {
namespace tree {

// Below the root: called only by the level-5 node's readTopology, which owns it from the moment it is made.
template <>
void InternalNode<LeafNode<float, 3>, 4>::readTopology(std::istream& is, bool fromHalf) {
  CHOKELOOPS_READ_INTERNAL_TOPOLOGY(false)
}

// A child of the root: called only by RootNode::readTopology, which would lose it on an exception.
template <>
void InternalNode<InternalNode<LeafNode<float, 3>, 4>, 5>::readTopology(std::istream& is, bool fromHalf) {
  CHOKELOOPS_READ_INTERNAL_TOPOLOGY(true)
}

}  // namespace tree
}  // namespace OPENVDB_VERSION_NAME
}  // namespace openvdb
#undef CHOKELOOPS_READ_INTERNAL_TOPOLOGY

namespace chokeloops {
namespace {

std::atomic<unsigned long> g_blocks{0};

enum class Codec { blosc, zip };

[[noreturn]] void refuse(const std::string& what) { OPENVDB_THROW(openvdb::IoError, "corrupt value block: " << what); }

// Reads one block of `expected` bytes into `data`, or skips it when `data` is null (OpenVDB's seek mode).
void read_block(std::istream& is, char* data, std::size_t expected, Codec codec) {
  g_blocks.fetch_add(1, std::memory_order_relaxed);
  std::int64_t length = 0;
  if (!is.read(reinterpret_cast<char*>(&length), sizeof length)) refuse("the file ends before a block's length");
  if (length <= 0) {  // raw bytes
    if (length == std::numeric_limits<std::int64_t>::min()) refuse("a block's length is -2^63");
    if (std::uint64_t(-length) != expected) {
      std::ostringstream s;
      s << "a block of " << expected << " bytes claims " << -length << " raw bytes";
      refuse(s.str());
    }
    if (!data) {
      is.seekg(std::streamoff(expected), std::ios_base::cur);
    } else if (!is.read(data, std::streamsize(expected))) {
      refuse("the file ends inside a block");
    }
    return;
  }
  if (!data) {
    is.seekg(std::streamoff(length), std::ios_base::cur);
    return;
  }
  const std::uint64_t largest =
      codec == Codec::blosc ? std::uint64_t(expected) + BLOSC_MAX_OVERHEAD : std::uint64_t(compressBound(uLong(expected)));
  if (std::uint64_t(length) > largest) {
    std::ostringstream s;
    s << "a block of " << expected << " bytes claims " << length << " compressed bytes";
    refuse(s.str());
  }
  std::unique_ptr<char[]> packed(new char[std::size_t(length)]);
  if (!is.read(packed.get(), std::streamsize(length))) refuse("the file ends inside a block");
  if (codec == Codec::blosc) {
    std::size_t nbytes = 0;
    if (blosc_cbuffer_validate(packed.get(), std::size_t(length), &nbytes) != 0 || nbytes != expected)
      refuse("a blosc block's header does not match its length or the values it holds");
    const int got = blosc_decompress_ctx(packed.get(), data, expected, /*numinternalthreads=*/1);
    if (got < 0 || std::size_t(got) != expected) refuse("a blosc block does not decompress");
  } else {
    uLongf got = uLongf(expected);
    const int status = uncompress(reinterpret_cast<Bytef*>(data), &got, reinterpret_cast<const Bytef*>(packed.get()),
                                  uLong(length));
    if (status != Z_OK || got != expected) refuse("a zlib block does not decompress");
  }
}

// Metadata. OpenVDB 10 also allocates whatever a metadata string or value claims (up to 4 GiB each, from a file
// of a few KB: fuzzing found a 1.7 GB name) and the delayed-load table every file carries sizes its vectors by a
// leaf count from the file. MetaMap::readMeta and DelayedLoadMetadata::readValue are exported and called through
// the library's linkage table and vtable, so they are replaced the same way: every length is checked against the
// bytes the file has left (and the table's leaf count against what the file can hold: 64 bytes of mask a leaf)
// before anything is allocated.
std::atomic<unsigned long> g_metamaps{0};

[[noreturn]] void refuse_meta(const std::string& what) { OPENVDB_THROW(openvdb::IoError, "corrupt metadata: " << what); }

// Bytes left in `is` after its position.
std::uint64_t bytes_left(std::istream& is) {
  const std::streampos here = is.tellg();
  if (here < 0) refuse_meta("the file ends in its metadata");
  is.seekg(0, std::ios_base::end);
  const std::streampos end = is.tellg();
  is.seekg(here);
  return end > here ? std::uint64_t(end - here) : 0;
}

std::uint32_t read_u32(std::istream& is) {
  std::uint32_t v = 0;
  if (!is.read(reinterpret_cast<char*>(&v), sizeof v)) refuse_meta("the file ends in its metadata");
  return v;
}

std::string read_string(std::istream& is) {
  const std::uint32_t n = read_u32(is);
  if (n > bytes_left(is)) refuse_meta("a name of " + std::to_string(n) + " bytes, more than the file has left");
  std::string s(n, '\0');
  if (n > 0 && !is.read(&s[0], n)) refuse_meta("the file ends in its metadata");
  return s;
}

// OpenVDB reads the topology (counts of tiles and children, node masks, raw values) without looking at the
// stream's state: past the end of the file a count of 2^32 children goes on allocating nodes (fuzzing: 1.4 GB from
// 33 KB). The first metadata read of a file, before any topology, makes the stream throw when a read fails, so
// every read past the end stops the reader, and what it allocates stays in proportion to the file.
void read_meta_map(openvdb::MetaMap& map, std::istream& is) {
  g_metamaps.fetch_add(1, std::memory_order_relaxed);
  is.exceptions(std::ios_base::failbit | std::ios_base::badbit);
  map.clearMetadata();
  const std::uint32_t count = read_u32(is);
  for (std::uint32_t i = 0; i < count; ++i) {
    const std::string name = read_string(is);
    const std::string type = read_string(is);
    const std::uint32_t size = read_u32(is);  // the value's length, read again by Metadata::read
    if (size > bytes_left(is))
      refuse_meta("'" + name + "' claims " + std::to_string(size) + " bytes, more than the file has left");
    is.seekg(-std::streamoff(sizeof size), std::ios_base::cur);
    if (openvdb::Metadata::isRegisteredType(type)) {
      openvdb::Metadata::Ptr value = openvdb::Metadata::createMetadata(type);
      value->read(is);
      if (!is) refuse_meta("the file ends in its metadata");
      map.insertMeta(name, *value);
    } else {
      openvdb::UnknownMetadata value(type);
      value.read(is);
      if (!is) refuse_meta("the file ends in its metadata");
      if (type.compare(0, 2, "__") != 0) map.insertMeta(name, value);  // "__" types are temporary, as in OpenVDB
    }
  }
}

// The delayed-load table: a leaf count, then a table of one byte a leaf and one of 8 bytes a leaf (the second
// may be absent: length 0xffffffff), each raw (length 0) or blosc compressed (its length), all within `size`.
void read_delayed_load(openvdb::io::DelayedLoadMetadata& table, std::istream& is, std::uint32_t size) {
  table.clear();
  if (size == 0) return;
  const std::streampos start = is.tellg();
  const std::uint64_t file = std::uint64_t(std::max<std::streamoff>(start, 0)) + bytes_left(is);
  if (size > bytes_left(is)) refuse_meta("the delayed-load table is longer than the file");
  std::uint64_t used = 0;
  auto room = [&](std::uint64_t n) {  // before anything of that size is allocated
    if (used + n > size) refuse_meta("the delayed-load table overruns its " + std::to_string(size) + " bytes");
  };
  auto take = [&](void* to, std::uint64_t n) {
    room(n);
    if (n > 0 && !is.read(static_cast<char*>(to), std::streamsize(n))) refuse_meta("the file ends in its metadata");
    used += n;
  };
  std::uint32_t count = 0, length = 0;
  take(&count, 4);
  if (count > file / 64 + 1)
    refuse_meta("the delayed-load table claims " + std::to_string(count) + " leaves, more than the file holds");
  auto read_table = [&](std::size_t item, std::uint32_t packed_length) {
    room(packed_length == 0 ? std::uint64_t(count) * item : packed_length);
    std::vector<char> raw(std::size_t(count) * item);
    if (packed_length == 0) {
      take(raw.data(), raw.size());
      return raw;
    }
    std::vector<char> packed(packed_length);
    take(packed.data(), packed.size());
    // OpenVDB's writer pads a table shorter than 128 bytes to 128 before compressing it
    std::size_t nbytes = 0;
    if (blosc_cbuffer_validate(packed.data(), packed.size(), &nbytes) != 0 || nbytes < raw.size() ||
        nbytes > std::max<std::size_t>(raw.size(), 128))
      refuse_meta("a blosc block of the delayed-load table does not match its length or its leaf count");
    std::vector<char> unpacked(nbytes);
    if (nbytes > 0 && blosc_decompress_ctx(packed.data(), unpacked.data(), nbytes, 1) != int(nbytes))
      refuse_meta("a blosc block of the delayed-load table does not decompress");
    std::copy(unpacked.begin(), unpacked.begin() + std::ptrdiff_t(raw.size()), raw.begin());
    return raw;
  };
  take(&length, 4);
  const std::vector<char> masks = read_table(sizeof(openvdb::io::DelayedLoadMetadata::MaskType), length);
  table.resizeMask(count);
  for (std::uint32_t i = 0; i < count; ++i) table.setMask(i, openvdb::io::DelayedLoadMetadata::MaskType(masks[i]));
  take(&length, 4);
  if (length != std::numeric_limits<std::uint32_t>::max()) {
    using Size = openvdb::io::DelayedLoadMetadata::CompressedSizeType;
    const std::vector<char> sizes = read_table(sizeof(Size), length);
    table.resizeCompressedSize(count);
    for (std::uint32_t i = 0; i < count; ++i) {
      Size v;
      std::memcpy(&v, sizes.data() + std::size_t(i) * sizeof v, sizeof v);
      table.setCompressedSize(i, v);
    }
  }
  if (used < size && !is.ignore(std::streamsize(size - used))) refuse_meta("the file ends in its metadata");
}

// Names OpenVDB reads inside functions that set private members and so cannot be rewritten here: a grid
// descriptor's names (GridDescriptor::read) and a transform's type (Transform::read). Their lengths are checked
// against the file, the stream is put back, and OpenVDB's own definition (the next one, dlsym RTLD_NEXT) reads.
void check_names(std::istream& is, int count) {
  const std::streampos start = is.tellg();
  for (int i = 0; i < count; ++i) {
    const std::uint32_t n = read_u32(is);
    if (n > bytes_left(is)) refuse_meta("a name of " + std::to_string(n) + " bytes, more than the file has left");
    is.seekg(std::streamoff(n), std::ios_base::cur);
  }
  is.seekg(start);
}

// The root node. OpenVDB's header code reads a root tile's active flag straight into a bool: a byte other than 0
// or 1 there is undefined behaviour (UBSan found it). Within a VdbRootCheck, each grid descriptor OpenVDB reads is
// noted, and when the transform of a float grid that is not an instance has been read, what follows is that
// grid's topology: a buffer count (1 since file format 222), the background, the tile and child counts and the
// tiles (coordinates, value, flag), which are checked here first.
struct GridPlace {
  const std::istream* stream;
  std::int64_t grid_pos;
  bool float_grid;
};
thread_local std::vector<GridPlace>* t_places = nullptr;

void note_grid(const std::istream& is, const openvdb::io::GridDescriptor& d) {
  if (t_places) t_places->push_back({&is, d.getGridPos(), d.gridType() == "Tree_float_5_4_3" && !d.isInstance()});
}

void check_float_root(std::istream& is, std::streampos transform_at) {
  if (!t_places || openvdb::io::getFormatVersion(is) < openvdb::OPENVDB_FILE_VERSION_NODE_MASK_COMPRESSION) return;
  // The grid being read is the one that starts last before its transform. Not "and whose blocks start after it":
  // a corrupt block position put the transform past it, and the float grid's tiles went unchecked (found by
  // fuzzing: a flag of 40). When no grid claims to start before it (a corrupt grid position, found next: a flag
  // of 135), the last grid described on this stream is the one read.
  const std::int64_t at = std::int64_t(transform_at);
  const GridPlace *reading = nullptr, *last = nullptr;
  for (const GridPlace& p : *t_places) {
    if (p.stream != &is) continue;
    last = &p;
    if (p.grid_pos <= at && (!reading || p.grid_pos > reading->grid_pos)) reading = &p;
  }
  if (!reading) reading = last;
  if (!reading || !reading->float_grid) return;
  const std::streampos start = is.tellg();
  const std::uint32_t buffers = read_u32(is);
  if (buffers != 1) refuse_meta("the tree claims " + std::to_string(buffers) + " buffers, not 1");
  is.seekg(sizeof(float), std::ios_base::cur);  // the background
  const std::uint32_t tiles = read_u32(is);
  read_u32(is);  // children
  constexpr std::uint64_t kTile = 3 * 4 + sizeof(float) + 1;
  if (std::uint64_t(tiles) * kTile > bytes_left(is))
    refuse_meta("the root claims " + std::to_string(tiles) + " tiles, more than the file holds");
  for (std::uint32_t i = 0; i < tiles; ++i) {
    char tile[kTile];
    is.read(tile, kTile);
    if (tile[kTile - 1] != 0 && tile[kTile - 1] != 1)
      refuse_meta("a root tile's active flag is " + std::to_string(int(static_cast<unsigned char>(tile[kTile - 1]))) +
                  ", neither 0 nor 1");
  }
  is.seekg(start);
}

template <class Fn>
Fn openvdb_definition(const std::string& mangled_tail) {  // after "_ZN7openvdb" and the version namespace
  const std::string ns = OPENVDB_PREPROC_STRINGIFY(OPENVDB_VERSION_NAME);
  const std::string symbol = "_ZN7openvdb" + std::to_string(ns.size()) + ns + mangled_tail;
  void* f = dlsym(RTLD_NEXT, symbol.c_str());
  if (!f) OPENVDB_THROW(openvdb::RuntimeError, "OpenVDB's " << symbol << " is not found");
  return reinterpret_cast<Fn>(f);
}

// One leaf's worth of values (some active, some not, so that mask compression is used), written with
// `compression` into memory and read back through OpenVDB's own stream reader.
bool round_trip(std::uint32_t compression) {
  auto grid = openvdb::FloatGrid::create(3.f);
  for (int i = 0; i < 8; ++i) grid->tree().setValue(openvdb::Coord(i, i % 3, 1), 0.25f * float(i) - 1.f);
  std::ostringstream os(std::ios::binary);
  openvdb::io::Stream writer(os);
  writer.setCompression(compression);
  writer.write({grid});
  const unsigned long before = g_blocks.load(), maps_before = g_metamaps.load(), topologies_before = g_topologies.load();
  std::istringstream is(os.str(), std::ios::binary);
  openvdb::io::Stream reader(is);
  auto grids = reader.getGrids();
  if (g_blocks.load() == before || g_metamaps.load() == maps_before || g_topologies.load() == topologies_before ||
      !grids || grids->size() != 1)
    return false;
  auto back = openvdb::gridPtrCast<openvdb::FloatGrid>(grids->front());
  if (!back || back->activeVoxelCount() != grid->activeVoxelCount()) return false;
  for (auto it = grid->cbeginValueOn(); it; ++it)
    if (back->tree().getValue(it.getCoord()) != *it) return false;
  return true;
}

}  // namespace

void require_vdb_guard(const std::string& path) {
  static std::once_flag flag;
  static bool in_place = false;
  static std::string why;
  std::call_once(flag, [] {
    ensure_openvdb_initialized();
    try {
      in_place = round_trip(openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK) &&
                 round_trip(openvdb::io::COMPRESS_ZIP | openvdb::io::COMPRESS_ACTIVE_MASK);
    } catch (const std::exception& e) {
      why = std::string(" (") + e.what() + ")";
    }
  });
  if (!in_place)
    throw InternalError("'" + path + "': not read: the guard against OpenVDB's unchecked block reader is not in "
                        "place in this build" + why);
}

unsigned long vdb_guard_blocks_read() { return g_blocks.load(); }

unsigned long vdb_guard_nodes_freed() { return g_freed.load(); }

VdbRootCheck::VdbRootCheck() {
  if (!t_places) t_places = new std::vector<GridPlace>();
}
VdbRootCheck::~VdbRootCheck() {
  delete t_places;
  t_places = nullptr;
}

}  // namespace chokeloops

// The readers OpenVDB's own calls reach (declared in openvdb/io/Compression.h, DelayedLoadMetadata.h,
// GridDescriptor.h, math/Transform.h and MetaMap.h). `numBytes` is the size of the buffer at `data` (null: skip the block).
namespace openvdb {
OPENVDB_USE_VERSION_NAMESPACE
namespace OPENVDB_VERSION_NAME {
namespace io {

void bloscFromStream(std::istream& is, char* data, size_t numBytes) {
  chokeloops::read_block(is, data, numBytes, chokeloops::Codec::blosc);
}

void unzipFromStream(std::istream& is, char* data, size_t numBytes) {
  chokeloops::read_block(is, data, numBytes, chokeloops::Codec::zip);
}

void DelayedLoadMetadata::readValue(std::istream& is, Index32 numBytes) {
  chokeloops::read_delayed_load(*this, is, numBytes);
}

GridBase::Ptr GridDescriptor::read(std::istream& is) {
  chokeloops::check_names(is, getFormatVersion(is) >= OPENVDB_FILE_VERSION_GRID_INSTANCING ? 3 : 2);
  using Fn = GridBase::Ptr (*)(GridDescriptor*, std::istream&);  // the Itanium ABI passes `this` first
  static const Fn next = chokeloops::openvdb_definition<Fn>("2io14GridDescriptor4readERSi");
  GridBase::Ptr grid = next(this, is);
  chokeloops::note_grid(is, *this);
  return grid;
}

}  // namespace io

void math::Transform::read(std::istream& is) {
  chokeloops::check_names(is, 1);
  using Fn = void (*)(math::Transform*, std::istream&);
  static const Fn next = chokeloops::openvdb_definition<Fn>("4math9Transform4readERSi");
  const std::streampos at = is.tellg();
  next(this, is);
  chokeloops::check_float_root(is, at);
}

void MetaMap::readMeta(std::istream& is) { chokeloops::read_meta_map(*this, is); }

}  // namespace OPENVDB_VERSION_NAME
}  // namespace openvdb
