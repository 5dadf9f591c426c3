#pragma once
// The memory budget every guard compares its estimate with: the machine's memory, the default share of it,
// and `--max-memory` values. Light on purpose (no OpenVDB), so that any stage can guard its allocations.
#include <cstddef>
#include <string>

namespace chokeloops {

std::size_t physical_memory_bytes();  // MemTotal from /proc/meminfo
std::size_t default_max_memory();     // 80% of physical memory
// Parses "8G", "512M", "1.5GiB", "1000000" (bytes); throws Error on nonsense.
std::size_t parse_bytes(const std::string& text);

}  // namespace chokeloops
