#include "chokeloops/huge_pages.h"

#include <malloc.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>

namespace chokeloops {

void restart_with_huge_pages(char** argv) {
  const char* opt = std::getenv("CHOKELOOPS_HUGE_PAGES");
  if (!opt || std::string(opt) != "1") return;  // opt-in: see huge_pages.h
  // Under valgrind the restarted process would run outside it (valgrind does not follow exec by default).
  const char* preload = std::getenv("LD_PRELOAD");
  if (preload && std::strstr(preload, "vgpreload")) return;
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  if (tunables && std::strstr(tunables, "glibc.malloc.hugetlb")) return;
  std::ifstream mode_file("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string mode;
  std::getline(mode_file, mode);
  if (mode.find("[madvise]") == std::string::npos) return;
  const std::string value = tunables && *tunables ? std::string(tunables) + ":glibc.malloc.hugetlb=1"
                                                  : std::string("glibc.malloc.hugetlb=1");
  if (setenv("GLIBC_TUNABLES", value.c_str(), 1) != 0) return;
  execv("/proc/self/exe", argv);
  // still here: the restart failed; run as is, and do not leave the variable to children that would not need it
  if (tunables) setenv("GLIBC_TUNABLES", tunables, 1);
  else unsetenv("GLIBC_TUNABLES");
}

void keep_freed_memory() {
  const char* opt = std::getenv("CHOKELOOPS_KEEP_FREED_MEMORY");
  if (opt && std::string(opt) == "0") return;
  mallopt(M_MMAP_MAX, 0);                 // large blocks from the heap, not from mmap
  mallopt(M_TRIM_THRESHOLD, 0x7fffffff);  // and freed ones kept there for reuse
}

}  // namespace chokeloops
