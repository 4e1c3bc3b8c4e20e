#include "lucent/image/metrics.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

#include "lucent/core/srgb.h"

namespace lucent {

namespace {

std::string joinNames(const std::vector<std::string>& names) {
  std::string s = "[";
  for (size_t i = 0; i < names.size(); ++i) s += (i ? ", " : "") + names[i];
  return s + "]";
}

// For each channel of `image`, the index of the same-named channel of `reference`.
std::vector<int> matchChannels(const Image& image, const Image& reference) {
  if (image.width() != reference.width() || image.height() != reference.height())
    throw std::invalid_argument(
        "image sizes differ: " + std::to_string(image.width()) + "x" +
        std::to_string(image.height()) + " vs reference " + std::to_string(reference.width()) +
        "x" + std::to_string(reference.height()));
  auto a = image.channels(), b = reference.channels();
  std::sort(a.begin(), a.end());
  std::sort(b.begin(), b.end());
  if (a != b)
    throw std::invalid_argument("image channels differ: " + joinNames(image.channels()) +
                                " vs reference " + joinNames(reference.channels()));
  std::vector<int> map;
  for (const std::string& name : image.channels()) map.push_back(reference.channelIndex(name));
  return map;
}

// Sums of the per-sample error terms; every metric is a function of their means.
struct ErrorSums {
  double sq = 0, abs = 0, rel = 0, smape = 0;
  void add(double v, double r) {
    const double d = v - r, denom = std::abs(v) + std::abs(r);
    sq += d * d;
    abs += std::abs(d);
    rel += d * d / ((r + 0.01) * (r + 0.01));
    smape += denom > 0 ? 2 * std::abs(d) / denom : 0.0;
  }
  void add(const ErrorSums& o) { sq += o.sq; abs += o.abs; rel += o.rel; smape += o.smape; }
  ChannelError mean(const std::string& channel, double count) const {
    const double n = std::max(count, 1.0);  // an empty image has zero error
    return {channel, std::sqrt(sq / n), abs / n, rel / n, smape / n};
  }
};

// Matplotlib's viridis (CC0) at nine evenly spaced points, sRGB-encoded.
constexpr std::array<std::array<float, 3>, 9> kViridis = {{{0.267f, 0.005f, 0.329f},
                                                           {0.282f, 0.140f, 0.458f},
                                                           {0.230f, 0.322f, 0.546f},
                                                           {0.173f, 0.449f, 0.558f},
                                                           {0.128f, 0.567f, 0.551f},
                                                           {0.158f, 0.684f, 0.502f},
                                                           {0.369f, 0.789f, 0.383f},
                                                           {0.678f, 0.864f, 0.190f},
                                                           {0.993f, 0.906f, 0.144f}}};

// Linear RGB, so that writePng's sRGB encoding reproduces the colour map.
std::array<float, 3> viridis(double t) {
  const double s = std::clamp(t, 0.0, 1.0) * (kViridis.size() - 1);
  const size_t i = std::min(size_t(s), kViridis.size() - 2);
  const float f = float(s - double(i));
  std::array<float, 3> rgb;
  for (int c = 0; c < 3; ++c)
    rgb[c] = srgbToLinear((1 - f) * kViridis[i][c] + f * kViridis[i + 1][c]);
  return rgb;
}

}  // namespace

ImageError compareImages(const Image& image, const Image& reference) {
  const std::vector<int> map = matchChannels(image, reference);
  for (const float v : reference.pixels())
    if (!std::isfinite(v)) throw std::invalid_argument("the reference has NaN or infinite values");
  const int channels = image.channelCount();
  std::vector<ErrorSums> sums(channels);
  std::vector<double> counted(channels, 0.0);
  ImageError result;
  for (int y = 0; y < image.height(); ++y)
    for (int x = 0; x < image.width(); ++x)
      for (int c = 0; c < channels; ++c) {
        const float v = image.at(x, y, c);
        if (!std::isfinite(v)) {
          ++result.nonFinite;
          continue;
        }
        sums[c].add(v, reference.at(x, y, map[c]));
        ++counted[c];
      }
  ErrorSums total;
  double all = 0;
  for (int c = 0; c < channels; ++c) {
    result.perChannel.push_back(sums[c].mean(image.channels()[c], counted[c]));
    total.add(sums[c]);
    all += counted[c];
  }
  result.overall = total.mean("all", all);
  return result;
}

ErrorMetric parseErrorMetric(const std::string& name) {
  using enum ErrorMetric;
  for (ErrorMetric m : {Rmse, Mae, RelMse, Smape})
    if (name == errorMetricName(m)) return m;
  throw std::invalid_argument("unknown error metric '" + name + "' (rmse, mae, relmse, smape)");
}

const char* errorMetricName(ErrorMetric metric) {
  switch (metric) {
    case ErrorMetric::Rmse: return "rmse";
    case ErrorMetric::Mae: return "mae";
    case ErrorMetric::RelMse: return "relmse";
    case ErrorMetric::Smape: return "smape";
  }
  return "?";
}

double errorValue(const ChannelError& error, ErrorMetric metric) {
  switch (metric) {
    case ErrorMetric::Rmse: return error.rmse;
    case ErrorMetric::Mae: return error.mae;
    case ErrorMetric::RelMse: return error.relmse;
    case ErrorMetric::Smape: return error.smape;
  }
  return 0;
}

Image errorHeatmap(const Image& image, const Image& reference, ErrorMetric metric,
                   double maxValue) {
  const std::vector<int> map = matchChannels(image, reference);
  const int w = image.width(), h = image.height();
  std::vector<double> error(size_t(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      ErrorSums sums;
      for (int c = 0; c < image.channelCount(); ++c)
        sums.add(image.at(x, y, c), reference.at(x, y, map[c]));
      error[size_t(y) * w + x] = errorValue(sums.mean("", image.channelCount()), metric);
    }

  double scale = maxValue;
  if (!(scale > 0)) {
    // The 99th percentile keeps a few fireflies from turning the rest of the map dark.
    std::vector<double> finite;
    for (double e : error)
      if (std::isfinite(e)) finite.push_back(e);
    scale = 0;
    if (!finite.empty()) {
      auto p99 = finite.begin() + ptrdiff_t(0.99 * double(finite.size() - 1));
      std::nth_element(finite.begin(), p99, finite.end());
      scale = *p99 > 0 ? *p99 : *std::max_element(finite.begin(), finite.end());
    }
    if (!(scale > 0)) scale = 1;
  }

  Image heatmap(w, h, {"R", "G", "B"});
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double e = error[size_t(y) * w + x];
      const std::array<float, 3> rgb = std::isfinite(e) ? viridis(e / scale)
                                                        : std::array<float, 3>{1, 0, 1};
      for (int c = 0; c < 3; ++c) heatmap.at(x, y, c) = rgb[c];
    }
  return heatmap;
}

}  // namespace lucent
