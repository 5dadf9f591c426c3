#pragma once
// Front-ends call restart_with_huge_pages(argv) first in main(): the process restarts itself once with
// glibc's malloc backing its large blocks by transparent huge pages.
//
// Why: the engine allocates its grids, complexes and meshes once and touches every page of them. On the
// virtual machines this runs on, a 4 KiB page fault costs ~10 µs, and faults were 40-50% of a run
// (gramicidin at 0.25 Å: 948 ms -> 477 ms median end to end, maltoporin 44 s -> 26 s). With the kernel's
// THP mode "madvise" (Debian's default), memory is huge-page backed only where the program asks with
// madvise(MADV_HUGEPAGE), which glibc does for malloc when its tunable glibc.malloc.hugetlb=1 is set; glibc
// reads tunables only at start-up, hence the restart. Nothing happens when the tunable is already set, when
// THP is "always" or "never", under valgrind, when CHOKELOOPS_HUGE_PAGES=0, or when the restart fails (the
// run goes on).
namespace chokeloops {

void restart_with_huge_pages(char** argv);

}  // namespace chokeloops
