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

// Front-ends call keep_freed_memory() before a run whose stages each allocate and free hundreds of megabytes
// (the molecule pipeline): glibc's malloc then serves large blocks from its heap and keeps what is freed for
// the next stage, instead of mapping fresh pages for each block and returning them when it is freed. On these
// virtual machines a fresh page costs a fault and the kernel's clearing (a fifth of a maltoporin run, `perf`:
// clear_page_erms), a reused one neither. Maltoporin in alternated runs, 2026-12-03: 15.1/11.1/10.6 s without,
// 10.2/10.1/11.5 s with (the machine's speed swings: the gain is largest when fresh pages are slow), peak RSS
// 1.84 -> 1.86 GB. Not the default for every input: freed blocks that the heap cannot give back
// while a later one is live stay counted, and a rough field's persistence then peaked 30% higher (818 MB
// against 613 MB, past its memory guard's estimate). CHOKELOOPS_KEEP_FREED_MEMORY=0 turns it off.
void keep_freed_memory();

}  // namespace chokeloops
