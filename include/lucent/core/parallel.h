// Thread-count control and per-thread floating-point set-up for oneTBB workers.
#pragma once
#include <cstddef>
#include <memory>

namespace lucent {

// Keeps freed memory in the process's heap instead of returning it to the system, so that the
// large per-stage arrays of a render reuse pages already touched: first touches of fresh pages
// (page faults) are slow on virtual machines and serialise threads. Call once, at start-up.
void retainFreedMemory();

// Flushes denormals to zero on the calling thread (Embree is slow and warns otherwise).
void flushDenormals();

// Items per oneTBB task where each item is a few hundred nanoseconds of work (a pixel's sums, a
// photon, a point): enough to amortize a task's scheduling, small enough that a few thousand items
// still spread over every core. Results never depend on it.
inline constexpr size_t kItemsPerTask = 4096;

// The most worker threads a render may ask for.
inline constexpr int kMaxThreads = 4096;

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
