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
