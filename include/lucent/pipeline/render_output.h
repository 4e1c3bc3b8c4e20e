// What every rendering method returns, and its progress callback.
#pragma once
#include <functional>

#include "lucent/core/stats.h"
#include "lucent/image/image.h"

namespace lucent {

// Called from worker threads with the fraction of work done; must be thread-safe.
using ProgressFn = std::function<void(double)>;

struct RenderOutput {
  Image image;
  RenderStats stats;
  int sppDone = 0;
};

}  // namespace lucent
