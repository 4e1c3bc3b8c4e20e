// Pixel filters of other renderers, sampled by filter importance sampling: each camera sample's
// position in its pixel is drawn from the filter itself, so that a pixel is the plain mean of its
// own samples (weight 1 where the filter is non-negative), pixels stay independent and the
// variance layers stay exact. Every filter is separable, f(x, y) = f(x) f(y), as pbrt-v4, Cycles
// and three.js-family GPU path tracers use them:
//   box             radius 0.5 (Lucent's default)
//   tent            1 - |x| / r, radius 1 (three.js-family GPU path tracers' jitter)
//   gaussian        exp(-x^2 / (2 sigma^2)) - exp(-r^2 / (2 sigma^2)), radius 1.5, sigma 0.5 (pbrt-v4)
//   blackman-harris 0.35875 - 0.48829 cos(t) + 0.14128 cos(2t) - 0.01168 cos(3t),
//                   t = 2 pi (x / w + 1/2), width w = 2r = 1.5 (Cycles)
//   mitchell        Mitchell-Netravali of 2x / r, B = C = 1/3, radius 2 (pbrt-v4)
// The filter as sampled is the analytic one averaged over 4,096 bins of its support (a
// piecewise-constant density, drawn exactly). Mitchell's negative lobes give their samples the
// weight -integral|f| / integral f, the others integral|f| / integral f.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "lucent/core/math.h"

namespace lucent {

enum class PixelFilterKind : uint32_t { Box, Tent, Gaussian, BlackmanHarris, Mitchell };

// The name the command line and scene files use ("box", "tent", "gaussian", "blackman-harris",
// "mitchell").
const char* pixelFilterName(PixelFilterKind kind);
// The radius a filter has unless one is given (pixels).
double defaultFilterRadius(PixelFilterKind kind);
// The filter in one dimension, unnormalized, at x pixels from the pixel's centre (0 beyond the radius).
double filterValue1D(PixelFilterKind kind, double radius, double x);

struct PixelFilterSettings {
  PixelFilterKind kind = PixelFilterKind::Box;
  double radius = 0;  // 0: defaultFilterRadius(kind)
};

class PixelFilter {
 public:
  explicit PixelFilter(PixelFilterSettings settings = {});
  // The box of the pixel itself (radius 0.5), whose positions are the uniform pair as drawn.
  bool isBox() const { return cdf_.empty(); }
  double radius() const { return radius_; }
  // A camera sample's position in its pixel's coordinates (0 to 1 across the pixel; a filter wider
  // than the box reaches into its neighbours) from a uniform pair, and its weight. The pixel's box
  // returns `u` itself, weight 1.
  Vec2 position(Vec2 u, float& weight) const;

 private:
  float axis(float u, float& sign) const;

  PixelFilterKind kind_;
  double radius_;
  std::vector<float> cdf_;    // over the bins, from 0 to 1
  std::vector<float> signs_;  // of the filter in each bin
  float weight_ = 1;          // integral |f| / integral f along one axis
};

}  // namespace lucent
