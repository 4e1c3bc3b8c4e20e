// How a render runs beyond its method's options: the part of the image and of its camera samples
// that it covers (one part of a render split over processes or machines, merged by `lucent
// merge`), the film of an interrupted run to resume from, checkpoints, and a request to stop
// (SIGINT, SIGTERM). Every method takes one; the default is the whole render, uninterrupted.
#pragma once
#include <atomic>
#include <cstdint>
#include <functional>

#include "lucent/pipeline/pixel_rect.h"
#include "lucent/pipeline/render_output.h"

namespace lucent {

class Film;

struct RenderControl {
  ProgressFn progress;
  // The part: the pixels of `crop` (empty: the whole image), and of each pixel the camera samples
  // [firstSample, firstSample + sampleCount) of the method's spp (sampleCount 0: to the last).
  PixelRect crop;
  int firstSample = 0, sampleCount = 0;
  // The film of an earlier run of the same render and part, left by a checkpoint: its samples are
  // kept and the render goes on from where each pixel stopped.
  const Film* resume = nullptr;
  // Called every `checkpointSeconds` (0: never) at a point where the film holds whole samples of
  // whole pixels, with that film (the state a resumed run needs).
  double checkpointSeconds = 0;
  std::function<void(const Film&)> checkpoint;
  // Set from outside (a signal handler): every stage stops within a fraction of a second
  // (core/stop.h). An interruptible method's sampling returns the whole samples it has, with
  // RenderOutput::complete false; a stop before its sampling, or in another method, throws
  // RenderStopped.
  const std::atomic<bool>* stop = nullptr;

  bool stopRequested() const { return stop && stop->load(std::memory_order_relaxed); }
  bool isPart() const { return !crop.empty() || firstSample != 0 || sampleCount != 0; }
};

}  // namespace lucent
