// The persistence engine's allocator (common/huge_page_allocator.h): large blocks are mappings of their own,
// aligned to huge pages, and a vector on it keeps its values through growth, copies and moves like any other.
#include <gtest/gtest.h>

#include <cstdint>
#include <numeric>
#include <vector>

#include "common/huge_page_allocator.h"

using chokeloops::detail::HugePageAllocator;
using chokeloops::detail::kHugePage;

template <class T>
using BigVector = std::vector<T, HugePageAllocator<T>>;

TEST(HugePageAllocator, LargeBlocksAreAlignedToHugePagesAndSmallOnesWork) {
  HugePageAllocator<std::uint32_t> alloc;
  const std::size_t large = 3 * kHugePage / sizeof(std::uint32_t) + 5;  // not a whole number of huge pages
  std::uint32_t* p = alloc.allocate(large);
  EXPECT_EQ(std::uintptr_t(p) % kHugePage, 0u);
  for (std::size_t i = 0; i < large; ++i) p[i] = std::uint32_t(i * 7);  // every byte asked for is writable
  std::uint64_t sum = 0;
  for (std::size_t i = 0; i < large; ++i) sum += p[i];
  EXPECT_EQ(sum, 7 * std::uint64_t(large) * (large - 1) / 2);
  alloc.deallocate(p, large);
  std::uint32_t* q = alloc.allocate(10);
  q[9] = 42;
  EXPECT_EQ(q[9], 42u);
  alloc.deallocate(q, 10);
  std::uint32_t* empty = alloc.allocate(0);
  EXPECT_NE(empty, nullptr);
  alloc.deallocate(empty, 0);
}

TEST(HugePageAllocator, VectorKeepsItsValuesAcrossGrowthCopyAndMove) {
  BigVector<std::uint64_t> v;
  std::vector<std::uint64_t> reference;
  // push_back across the small/large boundary: every reallocation moves the values to a new kind of block
  for (std::uint64_t i = 0; i < 2 * kHugePage / sizeof(std::uint64_t) + 1000; ++i) {
    v.push_back(i * i);
    reference.push_back(i * i);
  }
  ASSERT_EQ(v.size(), reference.size());
  EXPECT_TRUE(std::equal(v.begin(), v.end(), reference.begin()));
  BigVector<std::uint64_t> copy = v;
  BigVector<std::uint64_t> moved = std::move(v);
  EXPECT_TRUE(std::equal(copy.begin(), copy.end(), reference.begin()));
  EXPECT_TRUE(std::equal(moved.begin(), moved.end(), reference.begin()));
  moved.resize(10);
  moved.shrink_to_fit();
  EXPECT_EQ(moved.back(), 81u);
  BigVector<std::uint64_t>().swap(copy);
  EXPECT_TRUE(copy.empty());
}
