// Piecewise-constant 1-D and 2-D distributions for discrete and continuous sampling.
#pragma once
#include <algorithm>
#include <cstdint>
#include <span>
#include <vector>

#include "lucent/core/math.h"

namespace lucent {

class Distribution1D {
 public:
  Distribution1D() = default;
  // Weights must be finite and non-negative; an all-zero input becomes uniform.
  explicit Distribution1D(std::span<const float> weights);

  uint32_t size() const { return static_cast<uint32_t>(func_.size()); }
  float total() const { return total_; }
  float weight(uint32_t i) const { return func_[i]; }

  // Index with probability weight(i) / total(); `remapped` receives u rescaled to [0,1) within the bin.
  uint32_t sampleDiscrete(float u, float* pmf = nullptr, float* remapped = nullptr) const;
  // The index alone (of a constructed, so non-empty, distribution): the first bin whose upper CDF
  // value exceeds u (zero-weight bins are never picked), by a binary search without data-dependent
  // branches (u is random: a branch per level would be mispredicted half the time).
  uint32_t pick(float u) const {
    const double* first = cdf_.data() + 1;
    size_t count = func_.size();
    while (count > 1) {
      const size_t half = count / 2;
      first = first[half] <= double(u) ? first + half : first;
      count -= half;
    }
    const auto i = static_cast<uint32_t>(first - (cdf_.data() + 1)) + (first[0] <= double(u));
    return std::min(i, size() - 1);
  }
  // u, picked as bin i, rescaled to [0,1) within the bin.
  float remap(uint32_t i, float u) const {
    const double width = cdf_[i + 1] - cdf_[i];
    const double r = width > 0 ? (double(u) - cdf_[i]) / width : 0.0;
    return std::clamp(static_cast<float>(r), 0.0f, 0x1.fffffep-1f);
  }
  float pmf(uint32_t i) const { return weightedTotal_ > 0 ? func_[i] / weightedTotal_ : 1.0f / size(); }

  // Continuous position in [0,1) with density func(x) / integral; returns the bin in `bin`.
  float sampleContinuous(float u, float* pdf = nullptr, uint32_t* bin = nullptr) const;
  float pdfContinuous(float x) const;

 private:
  uint32_t binOf(float x) const;

  std::vector<float> func_;
  std::vector<double> cdf_;  // size()+1 entries, cdf_[0] = 0, cdf_[size()] = 1
  float total_ = 0;          // sum of weights as given
  float weightedTotal_ = 0;  // sum used for normalisation; 0 when all weights are zero (then uniform)
};

// Density over [0,1)^2 proportional to a row-major nu x nv grid of weights (u along columns).
class Distribution2D {
 public:
  Distribution2D() = default;
  Distribution2D(std::span<const float> weights, uint32_t nu, uint32_t nv);
  Vec2 sample(Vec2 u, float* pdf) const;
  float pdf(Vec2 uv) const;
  float total() const { return marginal_.total(); }

 private:
  std::vector<Distribution1D> conditional_;
  Distribution1D marginal_;
  uint32_t nu_ = 0, nv_ = 0;
};

}  // namespace lucent
