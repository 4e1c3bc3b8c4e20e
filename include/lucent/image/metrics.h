// Image error metrics for comparing renders against references.
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "lucent/image/image.h"

namespace lucent {

struct ChannelError {
  std::string channel;
  double rmse = 0, mae = 0, relmse = 0, smape = 0;
};

// The channels of one image that the other lacks (variance channels aside): not compared.
struct ChannelsLeftOut {
  std::vector<std::string> image, reference;
};

struct ImageError {
  std::vector<ChannelError> perChannel;
  ChannelsLeftOut notCompared;
  ChannelError overall;  // over all pixels and the compared channels
  // Values of the image that are NaN or infinite: an error of the image, however small the
  // metrics over its other values are (they leave these out).
  uint64_t nonFinite = 0;
};

// relMSE = mean((v - r)^2 / (r + 0.01)^2); SMAPE = mean(2|v - r| / (|v| + |r|)), 0 where both are 0.
// Compares the channels both images have (variance channels aside): every one where their sets
// are equal; where they differ, both must hold R, G and B (another renderer's RGB or RGBA against
// a reference with layers), and the channels one has alone are listed in notCompared. Throws
// std::invalid_argument with a clear message for different sizes, channel sets that differ
// without R, G and B in both, or a reference with a non-finite value.
ImageError compareImages(const Image& image, const Image& reference);
// What compareImages (rgbOnly false) or the R, G, B comparisons of testWithinNoise and a report
// (rgbOnly true) would refuse of two images' sizes and channels, from their headers alone: throws
// std::invalid_argument as they do, before any pixel is read.
void checkComparable(const ImageHeader& image, const ImageHeader& reference, bool rgbOnly);

enum class ErrorMetric { Rmse, Mae, RelMse, Smape };
// "rmse", "mae", "relmse", "smape"; parseErrorMetric throws std::invalid_argument for other names.
ErrorMetric parseErrorMetric(const std::string& name);
const char* errorMetricName(ErrorMetric metric);
double errorValue(const ChannelError& error, ErrorMetric metric);

// False-colour (viridis) R,G,B image of the per-pixel error: the metric over the pixel's channels,
// divided by maxValue, or by the 99th percentile of the per-pixel errors when maxValue <= 0.
// Non-finite errors are magenta. Same size and channel checks as compareImages. The error shown
// as the colour map's top is stored in *scaleUsed when given.
Image errorHeatmap(const Image& image, const Image& reference, ErrorMetric metric,
                   double maxValue = 0, double* scaleUsed = nullptr);
// The heatmaps' colour map from 0 (left) to its top (right), for a colour bar.
Image heatmapColourBar(int width, int height);

// A candidate against a reference within both images' noise (lucent compare --test): per block of
// block x block pixels (smaller at the right and bottom edges) and channel the Welch statistic
// z = (c - r) / sqrt(var_c + var_r) of the block's sums, from the variance of each pixel's mean (the
// channels variance.R, .G, .B that --variance writes; the reference must have them, a candidate
// without them counts as exact), its two-sided p-value from the normal distribution; and per region
// (the whole image, then a grid x grid of tiles) the same statistic of the region's sums, which
// finds a bias far below one pixel's noise. Blocks, not pixels: a pixel's few samples of a
// heavy-tailed integrand (rare paths at low sample counts) give a variance far below the true one
// when they miss the rare paths, and single pixels are rejected by chance; a block's sums draw on
// block^2 times the samples. The Cornell box at 128 x 128 against 1,024 samples per pixel, path
// traced with independent samples, two seeds each: at 64 samples, blocks of 1 reject 50 and 60
// pixels of 16,384 (4.5 times alpha's share below alpha), of 4 x 4 0 and 1 (1.6 times), of 8 x 8
// none (0.8 times); at 16 samples 8 x 8 rejects none (2 times alpha's share below alpha), 4 x 4
// 2 and 4; at 256 samples both none. Hence 8 x 8 by default. The image passes at
// significance alpha when no block's p-value is below alpha / (2 * 3 * blocks) and no region's
// below alpha / (2 * 3 * regions) (Bonferroni over the channels, the blocks and the regions, alpha
// split between the two families).
struct RegionTest {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  double relativeDifference = 0;  // sum(c - r) / sum(r) over the region's R, G, B: its bias
  double z = 0, pValue = 1;       // of the channel with the least p-value
  bool rejected = false;
};
struct NoiseTest {
  double alpha = 0.01;
  int block = 8;
  bool candidateHasVariance = false;
  uint64_t pixels = 0, blocks = 0;
  uint64_t blocksRejectedAtAlpha = 0;  // p-value (Bonferroni over the channels) below alpha: about alpha of them by chance
  uint64_t blocksRejected = 0;         // below the corrected threshold
  double minBlockPValue = 1;
  std::vector<RegionTest> regions;     // the whole image, then the grid row by row
  bool passed = false;
  Image statistic;                     // one channel "z": per pixel its block's largest |z| of the channels
};
NoiseTest testWithinNoise(const Image& candidate, const Image& reference, double alpha, int grid = 4, int block = 8);

// An equivalence verdict for a biased candidate (lucent compare --within D): per region (the whole
// image, then a grid x grid of tiles) its relative difference from the reference,
// d = sum(c) / sum(r) - 1 over the region's R, G and B, and the (1 - 2 alpha) confidence interval
// d +- z_(1 - alpha) se, se from both images' variance layers by the delta method (each pixel's
// channels taken as fully correlated, (sum of the channels' standard deviations)^2, which bounds
// their sum's variance whatever their correlation; a candidate without variance layers counts as
// exact). A region is equivalent when its interval lies inside (-within, within): two one-sided
// tests at level alpha; the image passes when every region is (an intersection-union test, at
// level alpha without correction).
struct EquivalenceRegion {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  double relativeDifference = 0, low = 0, high = 0;
  bool equivalent = false;
};
struct EquivalenceTest {
  double within = 0, alpha = 0.01;
  bool candidateHasVariance = false;
  std::vector<EquivalenceRegion> regions;  // the whole image, then the grid row by row
  bool passed = false;
};
EquivalenceTest testEquivalence(const Image& candidate, const Image& reference, double within, double alpha,
                                int grid = 4);
// The z with probability alpha above it under the standard normal distribution, alpha in (0, 1).
double normalUpperQuantile(double alpha);
// The R, G, B channels of an image.
Image rgbChannels(const Image& image);
// The layer `name` of an image as an image of its own (lucent compare --layer): the channels
// name.R, .G, .B as R, G, B, and name.variance.R, .G, .B as variance.R, .G, .B where present. A
// name that is not a layer of the image is looked up as paths.name (the path tracer's --paths
// layers). Returns nullopt when the image has neither; throws std::invalid_argument when it has both.
std::optional<Image> layerImage(const Image& image, const std::string& name, std::string* resolvedName = nullptr);
// The layers of an image that have R, G and B channels ("" for the image's own), for messages.
std::vector<std::string> colourLayers(const Image& image);
// lucent compare's and report's --layer and --image-layer: the reference's layer `name` and the
// candidate's layer `candidateName` (default: `name`), each as an image of its own (layerImage); a
// candidate without a layer of that default name (another renderer's image of that part alone) is
// compared whole, its R, G, B and variance. Throws std::invalid_argument when the reference has no
// such layer or the candidate no layer `candidateName`, naming the layers it has.
struct LayerChoice {
  Image candidate, reference;
  std::string candidateLayer, referenceLayer;  // "" for an image's own R, G, B
};
LayerChoice chooseLayer(const Image& candidate, const Image& reference, const std::string& name,
                        const std::string& candidateName = "");
// False colour (viridis) of an image's first channel from 0 to `top`, magenta where not finite:
// testWithinNoise's statistic |z| to 5, a FLIP map to 1.
Image valueHeatmap(const Image& values, double top);

}  // namespace lucent
