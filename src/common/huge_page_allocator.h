#pragma once
// Transparent huge pages for the persistence engine's own large arrays (its saddle lists, records, columns),
// asked for block by block: this machine's kernel backs memory by 2 MiB pages only where madvise asks (THP
// "madvise"), and with 4 KiB pages each fresh page of these arrays cost a fault. Noisy 256^3, 2 threads,
// 2026-12-04: 10.4/10.8 s with 4 KiB pages against 9.4/8.9 s, each run after 25 s idle (the case where the
// malloc-wide opt-in of include/chokeloops/huge_pages.h lost), and classify, dim 0 and dim 2 each ~30% faster.
// Asking is a hint: where the kernel says no, memory is as before. Private to src/.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <new>

#include <sys/mman.h>

namespace chokeloops::detail {

constexpr std::size_t kHugePage = std::size_t(2) << 20;

// The whole huge pages inside [begin, begin + bytes), or an empty range.
inline bool huge_page_interior(const void* begin, std::size_t bytes, std::uintptr_t& from, std::uintptr_t& to) {
  from = (std::uintptr_t(begin) + kHugePage - 1) & ~std::uintptr_t(kHugePage - 1);
  to = (std::uintptr_t(begin) + bytes) & ~std::uintptr_t(kHugePage - 1);
  return to > from;
}

// For a block malloc gave and nothing has touched yet: its pages will be huge ones when first written. Only
// for blocks of kOwnMapping or more, which glibc's malloc always maps on their own (its mmap threshold grows
// to 32 MB at most): advice on its heap would outlive the block (see HugePageAllocator).
constexpr std::size_t kOwnMapping = std::size_t(64) << 20;
inline void advise_huge_pages(const void* begin, std::size_t bytes) {
  std::uintptr_t from, to;
  if (bytes >= kOwnMapping && huge_page_interior(begin, bytes, from, to))
    madvise(reinterpret_cast<void*>(from), to - from, MADV_HUGEPAGE);
}

// A std::allocator whose blocks of a huge page or more are mapped on their own, aligned to huge pages and
// advised before anything touches them, and unmapped when freed; smaller ones come from malloc as usual.
// (Not malloc's aligned_alloc: a block it carved from its heap would leave the advice on memory it later
// hands out in small pieces, each touch then taking a whole huge page.)
template <class T>
struct HugePageAllocator {
  using value_type = T;
  HugePageAllocator() = default;
  template <class U>
  HugePageAllocator(const HugePageAllocator<U>&) {}
  static std::size_t mapped_bytes(std::size_t n) { return (n * sizeof(T) + kHugePage - 1) & ~(kHugePage - 1); }
  T* allocate(std::size_t n) {
    if (n > (std::size_t(-1) - 2 * kHugePage) / sizeof(T)) throw std::bad_alloc();  // rounded up and mapped with a page more
    if (n * sizeof(T) < kHugePage) {
      if (void* p = std::malloc(n ? n * sizeof(T) : 1)) return static_cast<T*>(p);
      throw std::bad_alloc();
    }
    // map a huge page more than asked, then give back what lies before the first boundary and after the end
    const std::size_t bytes = mapped_bytes(n);
    void* raw = mmap(nullptr, bytes + kHugePage, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (raw == MAP_FAILED) throw std::bad_alloc();
    const std::uintptr_t start = std::uintptr_t(raw), aligned = (start + kHugePage - 1) & ~std::uintptr_t(kHugePage - 1);
    if (aligned > start) munmap(raw, aligned - start);
    if (const std::uintptr_t tail = start + kHugePage - aligned; tail > 0)
      munmap(reinterpret_cast<void*>(aligned + bytes), tail);
    madvise(reinterpret_cast<void*>(aligned), bytes, MADV_HUGEPAGE);
    return reinterpret_cast<T*>(aligned);
  }
  void deallocate(T* p, std::size_t n) {
    if (n * sizeof(T) < kHugePage) std::free(p);
    else munmap(p, mapped_bytes(n));
  }
  template <class U>
  bool operator==(const HugePageAllocator<U>&) const { return true; }
  template <class U>
  bool operator!=(const HugePageAllocator<U>&) const { return false; }
};

}  // namespace chokeloops::detail
