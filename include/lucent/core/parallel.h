// Thread-count control and per-thread floating-point set-up for oneTBB workers.
#pragma once
#include <memory>

namespace lucent {

// Keeps freed memory in the process's heap instead of returning it to the system, so that the
// large per-stage arrays of a render reuse pages already touched: first touches of fresh pages
// (page faults) are slow on virtual machines and serialise threads. Call once, at start-up.
void retainFreedMemory();

// Flushes denormals to zero on the calling thread (Embree is slow and warns otherwise).
void flushDenormals();

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
