// The pool behind DenseIntMap (dense_int_map.h).
#include "dense_int_map.h"

#include <mutex>

namespace chokeloops::detail {

struct DenseIntMap::Pool {
  std::mutex mutex;
  std::vector<Store*> free;
};

DenseIntMap::Pool& DenseIntMap::pool() {
  static Pool p;  // never destroyed before its maps: they live inside calls, not in statics
  return p;
}

DenseIntMap::Store* DenseIntMap::acquire(std::size_t keys) {
  if (keys > std::size_t(std::numeric_limits<int>::max())) throw std::length_error("DenseIntMap: more ids than an int holds");
  Store* store = nullptr;
  {
    std::lock_guard<std::mutex> lock(pool().mutex);
    if (!pool().free.empty()) {
      store = pool().free.back();
      pool().free.pop_back();
    }
  }
  if (!store) store = new Store;
  // The store may serve a bigger mesh than last time (the input mesh after the level set's surface).
  try {
    if (store->value.size() < keys) store->value.resize(keys, kAbsent);
  } catch (...) {
    give_back(store);
    throw;
  }
  return store;
}

void DenseIntMap::give_back(Store* store) noexcept {
  if (!store) return;
  for (int key : store->touched) store->value[std::size_t(key)] = kAbsent;
  store->touched.clear();
  std::lock_guard<std::mutex> lock(pool().mutex);
  try {
    pool().free.push_back(store);
  } catch (...) {
    delete store;
  }
}

void DenseIntMap::release_pool() noexcept {
  std::vector<Store*> stores;
  {
    std::lock_guard<std::mutex> lock(pool().mutex);
    stores.swap(pool().free);
  }
  for (Store* store : stores) delete store;
}

}  // namespace chokeloops::detail
