#pragma once
// The guard in front of OpenVDB 10's value-block reader (vdb_guard.cpp explains why and how).
#include <string>

namespace chokeloops {

// Throws InternalError unless the guarded block reader has taken the place of OpenVDB's in this process
// (checked once, by a round trip through blosc and zip compressed blocks): without it a corrupt .vdb file
// could overflow OpenVDB's buffers, so no .vdb file is read. `path` only names the file in the message.
void require_vdb_guard(const std::string& path);

// How many value blocks the guarded reader has read or skipped in this process (for tests).
unsigned long vdb_guard_blocks_read();

// How many children of a root node the guarded topology reader has freed in this process, each after a read
// inside it failed (OpenVDB 10 would have lost them; for tests).
unsigned long vdb_guard_nodes_freed();

// While one of these lives on a thread, the grids OpenVDB's file reader opens on that thread are noted, and the
// root node of every non-instance float grid it then reads is checked before OpenVDB reads it (vdb_guard.cpp).
class VdbRootCheck {
 public:
  VdbRootCheck();
  ~VdbRootCheck();
  VdbRootCheck(const VdbRootCheck&) = delete;
  VdbRootCheck& operator=(const VdbRootCheck&) = delete;
};

}  // namespace chokeloops
