// Image error metrics for comparing renders against references.
#pragma once
#include <string>
#include <vector>

#include "lucent/image/image.h"

namespace lucent {

struct ChannelError {
  std::string channel;
  double rmse = 0, mae = 0, relmse = 0, smape = 0;
};

struct ImageError {
  std::vector<ChannelError> perChannel;
  ChannelError overall;  // over all pixels and the compared channels
  // Values of the image that are NaN or infinite: an error of the image, however small the
  // metrics over its other values are (they leave these out).
  uint64_t nonFinite = 0;
};

// relMSE = mean((v - r)^2 / (r + 0.01)^2); SMAPE = mean(2|v - r| / (|v| + |r|)), 0 where both are 0.
// Compares the channels both images have in common only if the sets are equal; throws
// std::invalid_argument with a clear message for different sizes or channel sets, or for a
// reference with a non-finite value.
ImageError compareImages(const Image& image, const Image& reference);

enum class ErrorMetric { Rmse, Mae, RelMse, Smape };
// "rmse", "mae", "relmse", "smape"; parseErrorMetric throws std::invalid_argument for other names.
ErrorMetric parseErrorMetric(const std::string& name);
const char* errorMetricName(ErrorMetric metric);
double errorValue(const ChannelError& error, ErrorMetric metric);

// False-colour (viridis) R,G,B image of the per-pixel error: the metric over the pixel's channels,
// divided by maxValue, or by the 99th percentile of the per-pixel errors when maxValue <= 0.
// Non-finite errors are magenta. Same size and channel checks as compareImages.
Image errorHeatmap(const Image& image, const Image& reference, ErrorMetric metric,
                   double maxValue = 0);

}  // namespace lucent
