#include "methods/pathtrace/error_target.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "lucent/core/memory.h"

namespace lucent {

StreamSums::StreamSums(uint64_t pixels) {
  requireMemory(pixels * sizeof(Pixel), "the two sample streams' sums of --target-error",
                "lower the resolution");
  pixels_.resize(pixels);
}

namespace {

// An estimate of 1 / (r + 0.01)^2 from the means A and B of two independent streams of a pixel
// whose converged value is r, the fewer of whose samples are `fewer`. Each stream's mean alone,
// 1/2 (1 / (A + 0.01)^2 + 1 / (B + 0.01)^2): where one stream met a rare bright path (a caustic
// through glass) and the other did not, the other's mean is near r, while any estimate that
// includes the bright path is far above it and would hide the error (A - B)^2 measures. But
// 1 / (A + 0.01)^2 overestimates on average by about three times A's relative variance, which
// with few samples is large (a stream of 4 that found no light at all): there the product of the
// two, (A + 0.01)(B + 0.01), whose expected value is exactly (r + 0.01)^2 (the streams are
// independent). Measured on the Cornell box, its glossy variant and the ring at 8 to 256 samples
// per pixel, against references (tests/methods/test_error_target.cpp): each stream's own from 16
// samples a stream on (at 8 samples the Cornell box's estimate was 5x too high with it, 0.84x
// with the product); the product alone left the glass ball's caustics 2.5x too low, each stream's
// own within 1.4x.
double inverseSquare(double meanA, double meanB, double fewer) {
  if (fewer < 16) return 1 / ((meanA + 0.01) * (meanB + 0.01));
  return 0.5 * (1 / ((meanA + 0.01) * (meanA + 0.01)) + 1 / ((meanB + 0.01) * (meanB + 0.01)));
}

}  // namespace

std::vector<float> StreamSums::pixelRelMse() const {
  std::vector<float> error(pixels_.size());
  for (size_t i = 0; i < pixels_.size(); ++i) {
    const Pixel& p = pixels_[i];
    const double a = p.valid[0], b = p.valid[1];
    if (a == 0 || b == 0) continue;
    double sum = 0;
    for (int c = 0; c < 3; ++c) {
      const double meanA = p.sum[0][c] / a, meanB = p.sum[1][c] / b;
      const double variance = (meanA - meanB) * (meanA - meanB) * a * b / ((a + b) * (a + b));
      sum += variance * inverseSquare(meanA, meanB, std::min(a, b));
    }
    error[i] = float(sum / 3);
  }
  return error;
}

double meanRelMse(std::span<const float> pixelRelMse) {
  double sum = 0;
  for (const float e : pixelRelMse) sum += e;
  return pixelRelMse.empty() ? 0 : sum / double(pixelRelMse.size());
}

double errorRate(double before, uint64_t samplesBefore, double after, uint64_t samplesAfter) {
  if (!(before > 0 && after > 0) || samplesAfter <= samplesBefore) return 1;
  return std::clamp(std::log(before / after) / std::log(double(samplesAfter) / double(samplesBefore)), 1.0, 2.0);
}

namespace {

// The sum of f(i) for i in [0, n), in parallel, the same for any thread count: blocks of fixed
// size summed in parallel, then the blocks' sums in order.
template <typename F>
double deterministicSum(size_t n, F f) {
  constexpr size_t kBlock = 4096;
  std::vector<double> blocks((n + kBlock - 1) / kBlock);
  tbb::parallel_for(size_t(0), blocks.size(), [&](size_t b) {
    double sum = 0;
    for (size_t i = b * kBlock, end = std::min(n, i + kBlock); i < end; ++i) sum += f(i);
    blocks[b] = sum;
  });
  double sum = 0;
  for (const double block : blocks) sum += block;
  return sum;
}

// Each pixel's per-sample relative variance averaged over its (2r+1)^2 neighbourhood, itself left
// out, and no lower than a hundredth of the image's mean: a pixel whose neighbours showed no
// variance yet (a rare path not found in their first samples) still gets a tenth of the mean
// pixel's share of samples.
std::vector<double> neighbourhoodVariance(std::span<const double> v, int width, int height) {
  constexpr int r = 4;
  const size_t w1 = size_t(width) + 1;
  std::vector<double> integral(w1 * (size_t(height) + 1), 0.0);  // sums of v over [0, x) x [0, y)
  double total = 0;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const double value = v[size_t(y) * size_t(width) + size_t(x)];
      total += value;
      integral[size_t(y + 1) * w1 + size_t(x + 1)] =
          value + integral[size_t(y) * w1 + size_t(x + 1)] + integral[size_t(y + 1) * w1 + size_t(x)] -
          integral[size_t(y) * w1 + size_t(x)];
    }
  const double floor = 0.01 * total / double(v.size());
  std::vector<double> smoothed(v.size());
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const size_t x0 = size_t(std::max(0, x - r)), x1 = size_t(std::min(width, x + r + 1));
      const size_t y0 = size_t(std::max(0, y - r)), y1 = size_t(std::min(height, y + r + 1));
      const double window = integral[y1 * w1 + x1] - integral[y0 * w1 + x1] - integral[y1 * w1 + x0] + integral[y0 * w1 + x0];
      const double count = double((x1 - x0) * (y1 - y0));
      const size_t i = size_t(y) * size_t(width) + size_t(x);
      const double others = count > 1 ? std::max(0.0, window - v[i]) / (count - 1) : v[i];
      smoothed[i] = std::max(others, floor);
    }
  return smoothed;
}

}  // namespace

PassPlan planNextPass(std::span<const float> pixelRelMse, std::span<const uint32_t> taken, int width, int height,
                      double aim, double rate, uint64_t maxNewSamples, uint32_t maxPerPixel) {
  const size_t n = taken.size();
  PassPlan plan;
  plan.samples.assign(taken.begin(), taken.end());
  uint64_t takenTotal = 0;
  for (const uint32_t t : taken) takenTotal += t;
  plan.total = plan.totalForAim = takenTotal;
  plan.predictedRelMse = meanRelMse(pixelRelMse);
  std::vector<double> perSample(n);
  double varianceTotal = 0;
  for (size_t i = 0; i < n; ++i) varianceTotal += perSample[i] = double(pixelRelMse[i]) * taken[i];
  if (varianceTotal <= 0 || maxNewSamples == 0) return plan;
  std::vector<double> root = neighbourhoodVariance(perSample, width, height);
  for (double& s : root) s = std::sqrt(s);

  // Pixel i's samples for the scale c: c * root[i], no fewer than it has, no more than the cap.
  auto samplesAt = [&](double c, size_t i) { return std::clamp(c * root[i], double(taken[i]), double(std::max(taken[i], maxPerPixel))); };
  auto fallen = [rate](double ratio) { return rate == 1 ? ratio : std::pow(ratio, rate); };
  auto totalAt = [&](double c) { return deterministicSum(n, [&](size_t i) { return samplesAt(c, i); }); };
  auto predictedAt = [&](double c) {
    return deterministicSum(n, [&](size_t i) { return double(pixelRelMse[i]) * fallen(taken[i] / samplesAt(c, i)); }) /
           double(n);
  };
  // The scales from "no pixel changes" to "every pixel at the cap"; the smallest c whose
  // `reached(c)` holds, by bisection in log c (both functions are monotonic in c).
  double cLow = INFINITY, cHigh = 0;
  for (size_t i = 0; i < n; ++i) {
    cLow = std::min(cLow, taken[i] / root[i]);
    cHigh = std::max(cHigh, double(std::max(taken[i], maxPerPixel)) / root[i]);
  }
  auto smallestScale = [&](auto reached) {
    if (reached(cLow)) return cLow;
    if (!reached(cHigh)) return cHigh;
    double lo = std::log(cLow), hi = std::log(cHigh);
    for (int k = 0; k < 40; ++k) {  // to a relative 1e-10 over a range of 1e5 in c
      const double mid = 0.5 * (lo + hi);
      (reached(std::exp(mid)) ? hi : lo) = mid;
    }
    return std::exp(hi);
  };
  const double cAim = smallestScale([&](double c) { return predictedAt(c) <= aim; });
  plan.totalForAim = uint64_t(std::ceil(totalAt(cAim)));
  const double minTotal = double(takenTotal) + std::ceil(0.1 * double(takenTotal));
  const double maxTotal = double(takenTotal) + double(maxNewSamples);
  double c = cAim;
  if (totalAt(c) < minTotal) c = smallestScale([&](double s) { return totalAt(s) >= minTotal; });
  const bool limited = totalAt(c) > maxTotal;
  if (limited) {
    // The largest scale within the limit: just below the smallest one past it.
    c = smallestScale([&](double s) { return totalAt(s) > maxTotal; }) * (1 - 1e-9);
  }
  plan.total = 0;
  double predicted = 0;
  for (size_t i = 0; i < n; ++i) {
    // Whole pairs of samples, one per stream; rounded down where the limit holds the pass back.
    const double pairs = (samplesAt(c, i) - taken[i]) / 2;
    const uint64_t whole = uint64_t(limited ? std::floor(pairs) : std::round(pairs));
    plan.samples[i] = uint32_t(std::min<uint64_t>(taken[i] + 2 * whole, std::max(taken[i], maxPerPixel)));
    plan.total += plan.samples[i];
    predicted += double(pixelRelMse[i]) * fallen(double(taken[i]) / plan.samples[i]);
  }
  plan.predictedRelMse = predicted / double(n);
  return plan;
}

}  // namespace lucent
