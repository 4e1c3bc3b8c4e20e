// Thread-count control and per-thread floating-point set-up for oneTBB workers.
#pragma once
#include <memory>

namespace lucent {

// Flushes denormals to zero on the calling thread (Embree is slow and warns otherwise).
void flushDenormals();

// While alive: limits oneTBB to `threads` workers (0: all cores) and flushes denormals on every
// worker thread as it joins the arena.
class ParallelScope {
 public:
  explicit ParallelScope(int threads = 0);
  ~ParallelScope();
  int threads() const { return threads_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  int threads_;
};

}  // namespace lucent
