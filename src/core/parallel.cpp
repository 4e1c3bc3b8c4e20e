#include "lucent/core/parallel.h"

#include <malloc.h>
#include <pmmintrin.h>
#include <xmmintrin.h>

#include <tbb/global_control.h>
#include <tbb/info.h>
#include <tbb/task_scheduler_observer.h>

namespace lucent {

void retainFreedMemory() {
  // glibc serves blocks above the mmap threshold with fresh mappings and unmaps them when freed;
  // 32 MiB is the largest threshold it accepts. Trimming the heap top would return pages too.
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
}

void flushDenormals() {
  _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
  _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
}

namespace {
class DenormalObserver : public tbb::task_scheduler_observer {
 public:
  DenormalObserver() { observe(true); }
  ~DenormalObserver() override { observe(false); }
  void on_scheduler_entry(bool) override { flushDenormals(); }
};
}  // namespace

struct ParallelScope::Impl {
  tbb::global_control control;
  DenormalObserver observer;
  explicit Impl(int threads) : control(tbb::global_control::max_allowed_parallelism, size_t(threads)) {}
};

ParallelScope::ParallelScope(int threads)
    : threads_(threads > 0 ? threads : tbb::info::default_concurrency()) {
  flushDenormals();
  impl_ = std::make_unique<Impl>(threads_);
}

ParallelScope::~ParallelScope() = default;

}  // namespace lucent
