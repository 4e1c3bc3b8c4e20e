#include "lucent/image/metrics.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>
#include <stdexcept>

#include "image/channel_indices.h"
#include "lucent/core/srgb.h"

namespace lucent {

namespace {

std::string joinNames(const std::vector<std::string>& names) {
  std::string s = "[";
  for (size_t i = 0; i < names.size(); ++i) s += (i ? ", " : "") + names[i];
  return s + "]";
}

// Whether a channel is the variance of another (render --variance): a statistic of the pixel's
// estimate, not part of the image, so that an image compares with a reference that has them.
bool isVarianceChannel(const std::string& name) { return name.rfind("variance.", 0) == 0; }

// The channels that are compared (all but the variance channels), sorted.
std::vector<std::string> comparedChannels(const std::vector<std::string>& channels) {
  std::vector<std::string> names;
  for (const std::string& name : channels)
    if (!isVarianceChannel(name)) names.push_back(name);
  std::sort(names.begin(), names.end());
  return names;
}

bool hasRgb(const std::vector<std::string>& channels) {
  for (const char* name : {"R", "G", "B"})
    if (std::find(channels.begin(), channels.end(), name) == channels.end()) return false;
  return true;
}

// The channels one image has and the other has not (variance channels aside), or an error where
// the two cannot be compared: their sets may differ only where both hold R, G and B (another
// renderer's RGBA against a reference with layers), and then their common channels are compared.
ChannelsLeftOut channelsLeftOut(const std::vector<std::string>& image, const std::vector<std::string>& reference) {
  const std::vector<std::string> a = comparedChannels(image), b = comparedChannels(reference);
  ChannelsLeftOut out;
  if (a == b) return out;
  if (!hasRgb(a) || !hasRgb(b))
    throw std::invalid_argument("image channels differ: " + joinNames(image) + " vs reference " + joinNames(reference) +
                                " (images whose channels differ are compared by their R, G and B, which both need)");
  std::set_difference(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(out.image));
  std::set_difference(b.begin(), b.end(), a.begin(), a.end(), std::back_inserter(out.reference));
  return out;
}

// For each channel of `image`, the index of the same-named channel of `reference`; -1 for the
// variance channels and those the reference lacks, which are not compared.
std::vector<int> matchChannels(const Image& image, const Image& reference, ChannelsLeftOut* leftOut = nullptr) {
  requireSameSize(image, reference);
  const ChannelsLeftOut left = channelsLeftOut(image.channels(), reference.channels());
  std::vector<int> map;
  for (const std::string& name : image.channels())
    map.push_back(isVarianceChannel(name) ? -1 : reference.channelIndex(name));
  if (leftOut) *leftOut = left;
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
  ImageError result;
  const std::vector<int> map = matchChannels(image, reference, &result.notCompared);
  for (const float v : reference.pixels())
    if (!std::isfinite(v)) throw std::invalid_argument("the reference has NaN or infinite values");
  const int channels = image.channelCount();
  std::vector<ErrorSums> sums(channels);
  std::vector<double> counted(channels, 0.0);
  for (int y = 0; y < image.height(); ++y)
    for (int x = 0; x < image.width(); ++x)
      for (int c = 0; c < channels; ++c) {
        if (map[c] < 0) continue;
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
    if (map[c] < 0) continue;
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
                   double maxValue, double* scaleUsed) {
  const std::vector<int> map = matchChannels(image, reference);
  const int w = image.width(), h = image.height();
  std::vector<double> error(size_t(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      ErrorSums sums;
      int compared = 0;
      for (int c = 0; c < image.channelCount(); ++c)
        if (map[c] >= 0) sums.add(image.at(x, y, c), reference.at(x, y, map[c])), ++compared;
      error[size_t(y) * w + x] = errorValue(sums.mean("", compared), metric);
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
  if (scaleUsed) *scaleUsed = scale;

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

namespace {

// An image of some of another's channels: channel k named names[k], copied from channel from[k].
Image copyChannels(const Image& image, std::vector<std::string> names, const std::vector<int>& from) {
  Image out(image.width(), image.height(), std::move(names));
  for (int y = 0; y < image.height(); ++y)
    for (int x = 0; x < image.width(); ++x)
      for (size_t k = 0; k < from.size(); ++k) out.at(x, y, int(k)) = image.at(x, y, from[k]);
  return out;
}

}  // namespace

Image rgbChannels(const Image& image) {
  const std::array<int, 3> at = rgbIndices(image, "", "the image");
  return copyChannels(image, {"R", "G", "B"}, {at[0], at[1], at[2]});
}

Image heatmapColourBar(int width, int height) {
  Image bar(width, height, {"R", "G", "B"});
  for (int x = 0; x < width; ++x) {
    const std::array<float, 3> rgb = viridis(width > 1 ? double(x) / double(width - 1) : 0.0);
    for (int y = 0; y < height; ++y)
      for (int c = 0; c < 3; ++c) bar.at(x, y, c) = rgb[size_t(c)];
  }
  return bar;
}

Image valueHeatmap(const Image& values, double top) {
  Image heatmap(values.width(), values.height(), {"R", "G", "B"});
  for (int y = 0; y < values.height(); ++y)
    for (int x = 0; x < values.width(); ++x) {
      const double v = values.at(x, y, 0);
      const std::array<float, 3> rgb = std::isfinite(v) ? viridis(v / top) : std::array<float, 3>{1, 0, 1};
      for (int c = 0; c < 3; ++c) heatmap.at(x, y, c) = rgb[size_t(c)];
    }
  return heatmap;
}

std::optional<Image> layerImage(const Image& image, const std::string& name, std::string* resolvedName) {
  auto hasRgb = [&](const std::string& layer) {
    return image.channelIndex(layer + ".R") >= 0 && image.channelIndex(layer + ".G") >= 0 &&
           image.channelIndex(layer + ".B") >= 0;
  };
  const std::string inPaths = "paths." + name;
  if (hasRgb(name) && hasRgb(inPaths))
    throw std::invalid_argument("layer '" + name + "' is ambiguous: the image has '" + name + "' and '" + inPaths + "'");
  const std::string layer = hasRgb(name) ? name : hasRgb(inPaths) ? inPaths : "";
  if (layer.empty()) return std::nullopt;
  if (resolvedName) *resolvedName = layer;
  std::vector<std::string> channels = {"R", "G", "B"};
  std::vector<int> from = {image.channelIndex(layer + ".R"), image.channelIndex(layer + ".G"),
                           image.channelIndex(layer + ".B")};
  const std::array<int, 3> variance = {image.channelIndex(layer + ".variance.R"), image.channelIndex(layer + ".variance.G"),
                                       image.channelIndex(layer + ".variance.B")};
  if (variance[0] >= 0 && variance[1] >= 0 && variance[2] >= 0) {
    channels.insert(channels.end(), {"variance.R", "variance.G", "variance.B"});
    from.insert(from.end(), variance.begin(), variance.end());
  }
  return copyChannels(image, std::move(channels), from);
}

std::vector<std::string> colourLayers(const Image& image) {
  std::vector<std::string> layers;
  for (const std::string& channel : image.channels()) {
    if (channel.size() < 2 || channel.substr(channel.size() - 2) != ".R") continue;
    const std::string layer = channel.substr(0, channel.size() - 2);
    if (image.channelIndex(layer + ".G") >= 0 && image.channelIndex(layer + ".B") >= 0 &&
        layer.find(".variance") == std::string::npos && layer != "variance")
      layers.push_back(layer);
  }
  return layers;
}

LayerChoice chooseLayer(const Image& candidate, const Image& reference, const std::string& name,
                        const std::string& candidateName) {
  auto missing = [](const Image& image, const std::string& which, const std::string& layerName) {
    std::string known;
    for (const std::string& layer : colourLayers(image)) known += (known.empty() ? "" : ", ") + layer;
    return std::invalid_argument("the " + which + " has no layer '" + layerName + "' (its layers: " +
                                 (known.empty() ? "none" : known) + ")");
  };
  LayerChoice choice;
  std::optional<Image> r = layerImage(reference, name, &choice.referenceLayer);
  if (!r) throw missing(reference, "reference", name);
  choice.reference = std::move(*r);
  std::optional<Image> c = layerImage(candidate, candidateName.empty() ? name : candidateName, &choice.candidateLayer);
  if (!c && !candidateName.empty()) throw missing(candidate, "image", candidateName);
  if (!c) {
    // The candidate whole: its R, G, B and, where it has them, its variance channels.
    std::vector<std::string> channels;
    std::vector<int> from;
    for (const char* channel : {"R", "G", "B", "variance.R", "variance.G", "variance.B"})
      if (candidate.channelIndex(channel) >= 0) channels.push_back(channel), from.push_back(candidate.channelIndex(channel));
    c = copyChannels(candidate, std::move(channels), from);
  }
  choice.candidate = std::move(*c);
  return choice;
}

void checkComparable(const ImageHeader& image, const ImageHeader& reference, bool rgbOnly) {
  requireSameSize(image.width, image.height, reference.width, reference.height);
  if (!rgbOnly) {
    channelsLeftOut(image.channels, reference.channels);
    return;
  }
  for (const auto& [channels, role] : {std::pair(&image.channels, "the image"), std::pair(&reference.channels, "the reference")})
    for (const char* name : {"R", "G", "B"})
      if (std::find(channels->begin(), channels->end(), name) == channels->end())
        throw std::invalid_argument(std::string(role) + " has no " + name + " channel");
}

}  // namespace lucent
