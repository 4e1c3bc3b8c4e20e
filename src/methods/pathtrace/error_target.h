// Rendering to an error target (--target-error): how far the image is from the converged one,
// estimated from the image alone, and where the next pass's samples go.
//
// Each pixel's camera samples alternate between two streams whose random numbers are independent
// (the Sobol sampler scrambled with different keys, PathSampler keyed by streamPixel): the means A
// and B of the two streams are then independent estimates of the pixel, so (A - B)^2 says how far
// their mean is from the pixel's expected value, with either sampler. The spread of one stream's
// samples would not: a Sobol pixel's samples are not independent, and its mean varies less than
// their spread says.
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "lucent/core/math.h"

namespace lucent {

// The key of a pixel's second stream: its pixel number with the top bit set (never a pixel's).
inline constexpr uint64_t kSecondStream = uint64_t(1) << 63;

// Per pixel, the sums of the valid samples of each stream.
class StreamSums {
 public:
  explicit StreamSums(uint64_t pixels);
  void add(uint64_t pixel, int stream, Rgb light) {
    Pixel& p = pixels_[pixel];
    p.sum[stream] += light;
    ++p.valid[stream];
  }
  // The estimated relative squared error of each pixel's mean (both streams'), over R, G and B:
  // its term of lucent compare's relMSE against the converged image r, mean over c of
  // Var(mean_c) / (r_c + 0.01)^2. Var(mean) is estimated from the streams' means A and B:
  // E[(A - B)^2] = s^2 (1/a + 1/b) for a and b valid samples of per-sample variance s^2, and the
  // mean of all a + b samples has variance s^2 / (a + b); (r + 0.01)^2 by (A + 0.01)(B + 0.01).
  std::vector<float> pixelRelMse() const;
  uint64_t size() const { return pixels_.size(); }

 private:
  struct Pixel {
    Rgb sum[2];
    uint32_t valid[2] = {0, 0};
  };
  std::vector<Pixel> pixels_;
};

// The image's estimated relMSE: the mean of the pixels' (in a fixed order).
double meanRelMse(std::span<const float> pixelRelMse);

// The samples each pixel has after the next pass of an error-targeted render, from the samples it
// has (`taken`, each even), the pixels' estimated errors and the image's size. A pixel's error
// after t samples is predicted as its error now times (taken / t)^rate: rate 1 for independent
// samples, more where the Sobol sampler's error falls faster (errorRate). The samples go where
// they lower the predicted image error most per sample: t proportional to the square root of the
// per-sample relative variance (the minimum of sum(v / t) at a fixed sum(t)), that variance
// smoothed over the pixel's 9 x 9 neighbourhood without the pixel itself, so that a pixel's own
// samples, which are noisy, do not decide how many samples it gets. The pass is sized for a
// predicted image error of `aim`, adding at least a tenth of the samples taken so far (so that
// passes are not wasted on a handful of samples) and at most `maxNewSamples` (doubling the total
// at most, and what a time budget allows); no pixel goes past maxPerPixel. Counts are even (one
// more sample per stream). Returns taken where no sample may be added.
struct PassPlan {
  std::vector<uint32_t> samples;  // per pixel, after the pass
  uint64_t total = 0;             // their sum
  double predictedRelMse = 0;     // the image's after the pass
  uint64_t totalForAim = 0;       // the samples the aim needs by the prediction, for progress
};
PassPlan planNextPass(std::span<const float> pixelRelMse, std::span<const uint32_t> taken, int width, int height,
                      double aim, double rate, uint64_t maxNewSamples, uint32_t maxPerPixel);

// How fast the image's error fell from one pass to the next, as the exponent of its samples:
// log(before / after) / log(samplesAfter / samplesBefore), within [1, 2] (1 where either estimate
// is zero).
double errorRate(double before, uint64_t samplesBefore, double after, uint64_t samplesAfter);

}  // namespace lucent
