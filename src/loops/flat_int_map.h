#pragma once
// Private to src/loops: a map from non-negative ints to ints, open addressing with linear probing in one
// flat array. The shortener looks mesh ids (vertices, faces, half-edges) up in its band millions of times a
// loop; std::unordered_map's node per entry made those lookups cache misses and its inserts allocations.
// Nothing iterates it, so the order of its slots never shows in a result.
#include <cstdint>
#include <stdexcept>
#include <vector>

namespace chokeloops::detail {

class FlatIntMap {
 public:
  FlatIntMap() { slots_.assign(kInitial, Slot{kEmpty, 0}); }
  std::size_t size() const { return size_; }
  // Inserts key -> value unless the key is there; true when inserted.
  bool emplace(int key, int value) {
    if (key < 0) throw std::invalid_argument("FlatIntMap: negative key");
    Slot& s = slots_[index_of(key)];
    if (s.key == key) return false;
    s = Slot{key, value};
    if (++size_ * 2 > slots_.size()) grow();
    return true;
  }
  const int* find(int key) const {
    if (key < 0) return nullptr;
    const Slot& s = slots_[index_of(key)];
    return s.key == key ? &s.value : nullptr;
  }
  bool contains(int key) const { return find(key) != nullptr; }
  int at(int key) const {
    const int* v = find(key);
    if (!v) throw std::out_of_range("FlatIntMap::at: no such key");
    return *v;
  }
  // The value of key, inserted as 0 when absent.
  int& operator[](int key) {
    if (key < 0) throw std::invalid_argument("FlatIntMap: negative key");
    Slot* s = &slots_[index_of(key)];
    if (s->key != key) {
      *s = Slot{key, 0};
      if (++size_ * 2 > slots_.size()) {
        grow();
        s = &slots_[index_of(key)];
      }
    }
    return s->value;
  }

 private:
  static constexpr int kEmpty = -1;
  static constexpr std::size_t kInitial = 64;
  struct Slot { int key; int value; };
  std::vector<Slot> slots_;
  std::size_t size_ = 0;

  // The slot holding key, or the empty one where it would go.
  std::size_t index_of(int key) const {
    const std::size_t mask = slots_.size() - 1;
    std::size_t i = (std::uint32_t(key) * 0x9E3779B1u) & mask;
    while (slots_[i].key != key && slots_[i].key != kEmpty) i = (i + 1) & mask;
    return i;
  }
  void grow() {
    std::vector<Slot> old(slots_.size() * 2, Slot{kEmpty, 0});
    old.swap(slots_);
    for (const Slot& s : old)
      if (s.key != kEmpty) slots_[index_of(s.key)] = s;
  }
};

}  // namespace chokeloops::detail
