#pragma once
// Private to src/loops: a map from the ids of one mesh (vertices or faces, 0..keys-1) to ints, held in one
// array over every id, so that a look-up is one load. The shortener asks its band's maps millions of times
// a loop, and FlatIntMap's hash probes there were a third of its time (perf, the cage's necks). The arrays
// come from a pool and go back to it with only the slots the map touched reset: a map costs the ids it
// holds, not the mesh. The pool keeps as many arrays as maps were ever alive at once, 4 bytes an id each.
#include <cstddef>
#include <limits>
#include <stdexcept>
#include <utility>
#include <vector>

namespace chokeloops::detail {

class DenseIntMap {
 public:
  DenseIntMap() = default;
  explicit DenseIntMap(std::size_t keys) : store_(acquire(keys)) {}
  ~DenseIntMap() { give_back(std::exchange(store_, nullptr)); }
  DenseIntMap(DenseIntMap&& other) noexcept : store_(std::exchange(other.store_, nullptr)) {}
  DenseIntMap& operator=(DenseIntMap&& other) noexcept {
    if (this != &other) give_back(std::exchange(store_, std::exchange(other.store_, nullptr)));
    return *this;
  }
  DenseIntMap(const DenseIntMap&) = delete;
  DenseIntMap& operator=(const DenseIntMap&) = delete;
  // Frees the arrays the pool keeps (those of live maps stay with them): after a batch of calls.
  static void release_pool() noexcept;

  std::size_t size() const { return store_ ? store_->touched.size() : 0; }
  // Inserts key -> value unless the key is there; true when inserted.
  bool emplace(int key, int value) {
    int& slot = slot_of(key);
    if (slot != kAbsent) return false;
    if (value == kAbsent) throw std::invalid_argument("DenseIntMap: value reserved for absent keys");
    slot = value;
    store_->touched.push_back(key);
    return true;
  }
  const int* find(int key) const {
    if (!store_ || key < 0 || std::size_t(key) >= store_->value.size()) return nullptr;
    const int& v = store_->value[std::size_t(key)];
    return v == kAbsent ? nullptr : &v;
  }
  bool contains(int key) const { return find(key) != nullptr; }
  int at(int key) const {
    const int* v = find(key);
    if (!v) throw std::out_of_range("DenseIntMap::at: no such key");
    return *v;
  }
  // The value of key, inserted as 0 when absent.
  int& operator[](int key) {
    int& slot = slot_of(key);
    if (slot == kAbsent) slot = 0, store_->touched.push_back(key);
    return slot;
  }

 private:
  static constexpr int kAbsent = std::numeric_limits<int>::min();
  struct Store {
    std::vector<int> value;    // kAbsent where no key is
    std::vector<int> touched;  // the keys present, to reset when the store goes back
  };
  Store* store_ = nullptr;

  int& slot_of(int key) {
    if (!store_ || key < 0 || std::size_t(key) >= store_->value.size())
      throw std::out_of_range("DenseIntMap: key outside the map's id range");
    return store_->value[std::size_t(key)];
  }
  struct Pool;  // the stores given back, for the next maps
  static Pool& pool();
  static Store* acquire(std::size_t keys);
  static void give_back(Store* store) noexcept;
};

}  // namespace chokeloops::detail
