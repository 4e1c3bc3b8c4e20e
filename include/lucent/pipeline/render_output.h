// What every rendering method returns, and its progress callback.
#pragma once
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "lucent/core/stats.h"
#include "lucent/image/image.h"

namespace lucent {

// Called from worker threads with the fraction of work done; must be thread-safe.
using ProgressFn = std::function<void(double)>;

class Film;

struct RenderOutput {
  Image image;  // of the render's part (RenderControl): its crop's pixels
  RenderStats stats;
  int sppDone = 0;
  // The film the image was made of (its sums, for checkpoints and merges), and whether it holds
  // every sample of the part (false after a stop request).
  std::shared_ptr<const Film> film;
  bool complete = true;
  // What the method measured of its own render, recorded in the image's header as lucent:NAME and
  // in the summary (the path tracer's estimated_relmse and samples_spent with an error target).
  std::vector<std::pair<std::string, double>> measured;
};

}  // namespace lucent
