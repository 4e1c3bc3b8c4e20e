// FLIP, the perceptual difference of two images flipped back and forth in front of an observer
// (Andersson et al., "FLIP: A Difference Evaluator for Alternating Images", HPG 2020), and
// HDR-FLIP for high-dynamic-range images (Andersson et al., "Visualizing Errors in Rendered High
// Dynamic Range Images", Eurographics 2021 short papers). Per pixel an error in [0, 1].
#pragma once
#include <array>
#include <optional>
#include <vector>

#include "lucent/image/image.h"

namespace lucent {

// FLIP's default observer: a 0.7 m wide display of 3,840 pixels seen from 0.7 m, 67.02 pixels per
// degree of visual angle.
inline constexpr double kFlipPixelsPerDegree = 0.7 * (3840.0 / 0.7) * 3.14159265358979323846 / 180.0;

struct FlipOptions {
  double pixelsPerDegree = kFlipPixelsPerDegree;
  // LDR-FLIP takes linear values and clamps them to [0, 1] (a display's range: 8-bit images decoded
  // from sRGB); HDR-FLIP takes linear values in [0, 65536], exposes them over a range of exposures,
  // tone maps each with ACES and keeps each pixel's largest LDR-FLIP.
  bool hdr = true;
  // HDR-FLIP's exposure range in stops; computed from the reference where not given.
  std::optional<double> startExposure, stopExposure;
};

struct FlipResult {
  Image map;  // one channel, "flip"
  double mean = 0;
  // Percentiles of the errors weighted by themselves (FLIP's pooling, which ranks a few large
  // errors above many tiny ones): the least error e with sum(errors <= e) >= p * sum(errors).
  double weightedMedian = 0, weightedQuartile1 = 0, weightedQuartile3 = 0;
  bool hdr = false;
  double startExposure = 0, stopExposure = 0;  // HDR-FLIP only
  int exposures = 0;                           // HDR-FLIP only
  uint64_t nonFinite = 0;  // the candidate's pixels with a NaN or infinite value: error 1
};

// FLIP of a candidate's R, G, B against the reference's (linear values; same size). Throws
// std::invalid_argument for different sizes, a missing R, G or B channel, a reference with a
// non-finite value, a pixels-per-degree outside [1, 1000] or a start exposure above the stop.
FlipResult computeFlip(const Image& candidate, const Image& reference, const FlipOptions& options = {});

// The stages, for tests and for readers checking them against the papers.
namespace flip {

// Colour spaces of linear sRGB values, the reference white D65 (X_n, Y_n, Z_n) =
// (0.950428545, 1, 1.088900371): YCxCz (linearised CIELAB, the space of the contrast-sensitivity
// filters) and CIELAB with the Hunt adjustment (a and b scaled by L / 100).
std::array<float, 3> linearRgbToYCxCz(std::array<float, 3> rgb);
std::array<float, 3> yCxCzToLinearRgb(std::array<float, 3> ycxcz);
std::array<float, 3> linearRgbToHuntLab(std::array<float, 3> rgb);
// HyAB distance |dL| + sqrt(da^2 + db^2).
float hyab(std::array<float, 3> a, std::array<float, 3> b);
// The colour error of two filtered, Hunt-adjusted colours: HyAB^q_c (q_c = 0.7) mapped to [0, 1]
// piecewise linearly, p_t = 0.95 of the range for the errors below p_c = 0.4 of c_max, the
// HyAB^q_c of pure green and pure blue.
float colourError(std::array<float, 3> huntLabA, std::array<float, 3> huntLabB);

// One-dimensional factors of the separable two-dimensional filters, weights at -radius..radius.
// Contrast sensitivity (per channel, x in degrees = pixels / ppd): Y and Cx a Gaussian
// sqrt(pi / b) exp(-pi^2 x^2 / b) (b 0.0047 and 0.0053); Cz the sum of two, 34.1 (b 0.04) and
// 13.5 (b 0.025). The two-dimensional kernel of a channel is the sum over its Gaussians of
// factor(x) factor(y), normalised to sum to 1; one radius for all three channels,
// ceil(3 sqrt(0.04 / (2 pi^2)) ppd).
struct CsfFilters {
  int radius = 0;
  std::vector<float> y, cx, cz1, cz2;
};
CsfFilters csfFilters(double pixelsPerDegree);
// Feature detection on the luminance (Y / Y_n): a Gaussian of standard deviation 0.5 w ppd pixels
// (w = 0.082 degrees), radius ceil(3 sd), its first derivative (edges) and second (points), each
// derivative's positive weights normalised to sum to 1 and its negative ones to -1, the Gaussian
// to 1.
struct FeatureFilters {
  int radius = 0;
  std::vector<float> gaussian, edge, point;
};
FeatureFilters featureFilters(double pixelsPerDegree);
// Each pixel's edge and point strength (channels "edge", "point") of an image's luminance: the
// length of the vector of its correlations with the derivative kernel and its transpose.
Image featureStrengths(const Image& linearRgb, double pixelsPerDegree);

// ACES tone curve as HDR-FLIP applies it, (0.6 x)(2.51 (0.6 x) + 0.03) / ((0.6 x)(2.43 (0.6 x) + 0.59)
// + 0.14), clamped to [0, 1].
float acesToneMap(float x);
// HDR-FLIP's exposure range from the reference: start log2(x_t / Y_max), stop log2(x_t / Y_median)
// with ACES(x_t) = 0.85 and Y the luminance (the median of the positive luminances where more than
// half are 0; both 0 for a black reference).
std::array<double, 2> exposureRange(const Image& reference);

}  // namespace flip

}  // namespace lucent
