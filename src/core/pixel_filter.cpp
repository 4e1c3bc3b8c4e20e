#include "lucent/core/pixel_filter.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace lucent {

namespace {

constexpr int kBins = 4096;
constexpr double kPiDouble = 3.14159265358979323846;

// Mitchell and Netravali's cubic on |x| <= 2 (pbrt-v4's Mitchell1D).
double mitchell1D(double x, double b, double c) {
  x = std::abs(x);
  if (x <= 1)
    return ((12 - 9 * b - 6 * c) * x * x * x + (-18 + 12 * b + 6 * c) * x * x + (6 - 2 * b)) / 6;
  if (x <= 2)
    return ((-b - 6 * c) * x * x * x + (6 * b + 30 * c) * x * x + (-12 * b - 48 * c) * x + (8 * b + 24 * c)) / 6;
  return 0;
}

}  // namespace

const char* pixelFilterName(PixelFilterKind kind) {
  switch (kind) {
    case PixelFilterKind::Box: return "box";
    case PixelFilterKind::Tent: return "tent";
    case PixelFilterKind::Gaussian: return "gaussian";
    case PixelFilterKind::BlackmanHarris: return "blackman-harris";
    case PixelFilterKind::Mitchell: return "mitchell";
  }
  return "box";
}

double defaultFilterRadius(PixelFilterKind kind) {
  switch (kind) {
    case PixelFilterKind::Box: return 0.5;
    case PixelFilterKind::Tent: return 1.0;
    case PixelFilterKind::Gaussian: return 1.5;
    case PixelFilterKind::BlackmanHarris: return 0.75;
    case PixelFilterKind::Mitchell: return 2.0;
  }
  return 0.5;
}

double filterValue1D(PixelFilterKind kind, double radius, double x) {
  if (std::abs(x) > radius) return 0;
  switch (kind) {
    case PixelFilterKind::Box: return 1;
    case PixelFilterKind::Tent: return 1 - std::abs(x) / radius;
    case PixelFilterKind::Gaussian: {
      constexpr double sigma = 0.5;
      auto g = [](double v) { return std::exp(-v * v / (2 * sigma * sigma)); };
      return std::max(0.0, g(x) - g(radius));
    }
    case PixelFilterKind::BlackmanHarris: {
      const double t = 2 * kPiDouble * (x / (2 * radius) + 0.5);
      return 0.35875 - 0.48829 * std::cos(t) + 0.14128 * std::cos(2 * t) - 0.01168 * std::cos(3 * t);
    }
    case PixelFilterKind::Mitchell: return mitchell1D(2 * x / radius, 1.0 / 3, 1.0 / 3);
  }
  return 0;
}

PixelFilter::PixelFilter(PixelFilterSettings settings) : kind_(settings.kind) {
  radius_ = settings.radius > 0 ? settings.radius : defaultFilterRadius(kind_);
  if (!(radius_ > 0 && radius_ <= 16)) throw std::invalid_argument("a pixel filter's radius must lie in (0, 16]");
  if (kind_ == PixelFilterKind::Box && radius_ == 0.5) return;  // the pixel itself: positions as drawn
  // Each bin's mean of the filter (16 points), its magnitude's running sum, and its sign.
  cdf_.assign(kBins + 1, 0.0f);
  signs_.assign(kBins, 1.0f);
  double absolute = 0, integral = 0;
  std::vector<double> sums(kBins + 1, 0.0);
  for (int i = 0; i < kBins; ++i) {
    double mean = 0;
    for (int k = 0; k < 16; ++k) {
      const double x = -radius_ + 2 * radius_ * (i + (k + 0.5) / 16) / kBins;
      mean += filterValue1D(kind_, radius_, x) / 16;
    }
    signs_[size_t(i)] = mean < 0 ? -1.0f : 1.0f;
    absolute += std::abs(mean), integral += mean;
    sums[size_t(i) + 1] = absolute;
  }
  if (!(integral > 0)) throw std::invalid_argument(std::string("the ") + pixelFilterName(kind_) + " filter integrates to 0");
  for (int i = 0; i <= kBins; ++i) cdf_[size_t(i)] = float(sums[size_t(i)] / absolute);
  cdf_[kBins] = 1.0f;
  weight_ = float(absolute / integral);
}

float PixelFilter::axis(float u, float& sign) const {
  // The bin whose share of the magnitude holds u, then uniformly within it.
  const auto above = std::upper_bound(cdf_.begin() + 1, cdf_.end() - 1, u);
  const size_t bin = size_t(above - cdf_.begin()) - 1;
  const float low = cdf_[bin], high = cdf_[bin + 1];
  const float t = high > low ? std::clamp((u - low) / (high - low), 0.0f, 1.0f) : 0.5f;
  sign = signs_[bin];
  return float(-radius_ + 2 * radius_ * (double(bin) + double(t)) / kBins);
}

Vec2 PixelFilter::position(Vec2 u, float& weight) const {
  if (isBox()) {
    weight = 1;
    return u;
  }
  float signX = 1, signY = 1;
  const float x = axis(u.x, signX), y = axis(u.y, signY);
  weight = signX * signY * weight_ * weight_;
  return {0.5f + x, 0.5f + y};
}

}  // namespace lucent
