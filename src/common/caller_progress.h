#pragma once
// The progress of a stage that parallel workers run item by item (the loop stage, the label volumes), told
// through the thread that started the stage only: the hooks of the CLI (a bar on stderr) and of Python (Ctrl-C,
// a callback under the GIL) are not made for other threads. It is also the stage's stop: once the hook answers
// false, or anything throws, the workers take no new item, and the caller gets the first failure.
#include <atomic>
#include <cstddef>
#include <exception>
#include <mutex>
#include <thread>

#include "chokeloops/grid.h"
#include "chokeloops/topology/persistence.h"

namespace chokeloops::detail {

class CallerProgress {
 public:
  // To be made on the calling thread, before the workers start.
  CallerProgress(const ProgressFn& progress, const char* stage, std::size_t items)
      : progress_(progress), stage_(stage), items_(items), caller_(std::this_thread::get_id()) {}
  // Whether the workers should take no new item.
  bool stopped() const { return stop_; }
  // One item done, on any thread; on the caller's, the hook hears the fraction done.
  void item_done() {
    const std::size_t done = ++finished_;
    if (!progress_ || std::this_thread::get_id() != caller_) return;
    try {
      if (!progress_(stage_, double(done) / double(items_))) stop_ = true;
    } catch (...) {  // a hook that throws rather than answer false: its exception, as promptly
      fail(std::current_exception());
    }
  }
  // The first failure, on any thread, is kept for finish(); the workers stop.
  void fail(std::exception_ptr e) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!failure_) failure_ = e;
    stop_ = true;
  }
  // On the caller, once the workers are done: the first failure again, Error "interrupted" where the hook asked
  // to stop, else the hook hears 1.
  void finish() {
    if (failure_) std::rethrow_exception(failure_);
    if (stop_ || (progress_ && !progress_(stage_, 1.0))) throw Error("interrupted");
  }

 private:
  const ProgressFn& progress_;
  const char* stage_;
  std::size_t items_;
  std::thread::id caller_;
  std::atomic<std::size_t> finished_{0};
  std::atomic<bool> stop_{false};
  std::mutex mutex_;
  std::exception_ptr failure_;
};

}  // namespace chokeloops::detail
