// Stopping a render that is under way: a flag that SIGINT or SIGTERM (or another thread) sets, and
// that every stage long enough to matter polls between its work items. A stop in the middle of a
// stage throws RenderStopped, which unwinds the stage (oneTBB carries it out of parallel loops); the
// methods that keep a film between bands catch it there and return the bands they finished.
#pragma once
#include <atomic>
#include <stdexcept>

namespace lucent {

struct RenderStopped : std::runtime_error {
  RenderStopped() : std::runtime_error("the render was asked to stop") {}
};

namespace detail {
inline std::atomic<const std::atomic<bool>*> stopFlag{nullptr};
}

// While alive, `flag` (null: none) is the stop request that stopRequested() reads. One render at a
// time per process: a scope replaces the flag of any scope around it, and restores it at its end.
class StopScope {
 public:
  explicit StopScope(const std::atomic<bool>* flag) : previous_(detail::stopFlag.exchange(flag)) {}
  ~StopScope() { detail::stopFlag.store(previous_); }
  StopScope(const StopScope&) = delete;
  StopScope& operator=(const StopScope&) = delete;

 private:
  const std::atomic<bool>* previous_;
};

inline bool stopRequested() {
  const std::atomic<bool>* flag = detail::stopFlag.load(std::memory_order_relaxed);
  return flag && flag->load(std::memory_order_relaxed);
}

// A point where a stage may stop: throws RenderStopped once a stop is requested. Cheap enough for
// every chunk of a parallel loop.
inline void stopPoint() {
  if (stopRequested()) throw RenderStopped();
}

}  // namespace lucent
