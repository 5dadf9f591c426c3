#pragma once
// Disjoint sets over 0..n-1 with path halving; the smaller index is kept as the root, so the sets' roots do
// not depend on the order of the unions. Private to src/surface.
#include <algorithm>
#include <cstddef>
#include <numeric>
#include <vector>

namespace chokeloops {

struct UnionFind {
  std::vector<int> p;
  explicit UnionFind(std::size_t n) : p(n) { std::iota(p.begin(), p.end(), 0); }
  int find(int x) {
    while (p[std::size_t(x)] != x) x = p[std::size_t(x)] = p[std::size_t(p[std::size_t(x)])];
    return x;
  }
  // False when a and b were already in one set.
  bool unite(int a, int b) {
    a = find(a), b = find(b);
    if (a == b) return false;
    p[std::size_t(std::max(a, b))] = std::min(a, b);
    return true;
  }
};

}  // namespace chokeloops
