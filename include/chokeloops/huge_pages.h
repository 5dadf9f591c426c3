#pragma once
// Front-ends call restart_with_huge_pages(argv) first in main(): with CHOKELOOPS_HUGE_PAGES=1 the process
// restarts itself once with glibc's malloc backing its large blocks by transparent huge pages.
//
// Opt-in, because on the virtual machines this is measured on a fresh 2 MiB page is the dearest memory there
// is: after the machine idled it costs its first touch 0.3-0.5 GB/s (maltoporin's 1.8 GB: 4.6-4.7 s of
// system time), cheap only right after another process freed huge pages, against 1.4-2.1 GB/s for 4 KiB
// pages whatever ran before (1.0-1.2 s), and nothing came back in user time. Maltoporin at 0.25 Å after 8 s
// idle, alternated, 2026-12-03: 11.4/11.9/11.5 s with huge pages, 8.3/8.5/7.5 s without; back to back
// (bench_molecules, medians of 3) 9.0/9.1 against 9.0/7.9 s; gramicidin and the rough persistence at 256^3
// the same either way. (On an earlier state of the same machine, when a 4 KiB fault cost ~10 µs, they halved
// maltoporin's and gramicidin's times and were the default.) With THP in "madvise" mode (Debian's default)
// memory is huge-page backed only where the program asks with madvise(MADV_HUGEPAGE), which glibc does for
// malloc when its tunable glibc.malloc.hugetlb=1 is set; glibc reads tunables only at start-up, hence the
// restart. Nothing happens when the tunable is already set, when THP is "always" or "never", under valgrind,
// or when the restart fails (the run goes on).
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
