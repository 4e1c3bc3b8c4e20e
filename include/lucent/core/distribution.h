// Piecewise-constant 1-D and 2-D distributions for discrete and continuous sampling.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "lucent/core/math.h"

namespace lucent {

class Distribution1D {
 public:
  // The grid a uniform number u in [0, 1) lies on: u = k 2^-24 for an integer k (a float's 24
  // bits), as every sampler in Lucent draws it. Each bin owns a run of the grid's cells, about its
  // share of the weights, and its probability is its cells over the grid, exactly: the pick and
  // the pmf agree for any weights. A bin narrower than a cell, which no u could pick, has no cell
  // and pmf 0 (a light that MIS then leaves to BSDF sampling whole) instead of a pmf that an
  // estimator would divide by but never draw.
  static constexpr uint32_t kCells = 1u << 24;

  Distribution1D() = default;
  // Weights must be finite and non-negative; an all-zero input becomes uniform. A bin flagged in
  // `ownCell` (empty: none) whose weight is positive gets at least one cell however small its
  // weight: a point or directional light, which no other strategy samples, is never lost.
  explicit Distribution1D(std::span<const float> weights, std::span<const uint8_t> ownCell = {});

  uint32_t size() const { return static_cast<uint32_t>(func_.size()); }
  float total() const { return total_; }
  float weight(uint32_t i) const { return func_[i]; }

  // Where `cells` cells are shared out by weight, the `owners` bins that own a cell taking one each
  // first: the first cell of the bin whose predecessors weigh `before` (of `total`, positive) and of
  // which `ownersBefore` own a cell. Rounded up, as a u compared with the running sums would be.
  static uint32_t sharedCell(double before, double total, uint32_t ownersBefore, uint32_t owners, uint32_t cells) {
    const uint32_t spread = cells - owners;
    return ownersBefore + static_cast<uint32_t>(std::min(std::ceil(before * spread / total), double(spread)));
  }
  // The grid cell that u falls in (u below 2^-24 apart in the cell below, as a coarser u's would).
  static uint32_t cellOf(float u) { return std::min(static_cast<uint32_t>(u * 0x1p24f), kCells - 1); }

  // Index with probability pmf(i); `remapped` receives u rescaled to [0,1) within the bin.
  uint32_t sampleDiscrete(float u, float* pmf = nullptr, float* remapped = nullptr) const;
  // The index alone (of a constructed, so non-empty, distribution): the bin whose cells hold u's
  // (bins without cells are never picked), by a binary search without data-dependent branches (u
  // is random: a branch per level would be mispredicted half the time).
  uint32_t pick(float u) const { return pickCell(cellOf(u)); }
  uint32_t pickCell(uint32_t cell) const {
    const uint32_t* first = cells_.data() + 1;
    size_t count = func_.size();
    while (count > 1) {
      const size_t half = count / 2;
      first = first[half] <= cell ? first + half : first;
      count -= half;
    }
    return static_cast<uint32_t>(first - (cells_.data() + 1)) + (first[0] <= cell);
  }
  // u, picked as bin i, rescaled to [0,1) within the bin's cells. It takes as many values as the
  // bin has cells (u's own): a bin of few cells, one of a tiny probability, gets a coarse number.
  float remap(uint32_t i, float u) const {
    const double r = (double(u) * kCells - cells_[i]) / double(cells_[i + 1] - cells_[i]);
    return std::clamp(static_cast<float>(r), 0.0f, 0x1.fffffep-1f);
  }
  float pmf(uint32_t i) const { return float(cellCount(i)) * 0x1p-24f; }
  uint32_t cellCount(uint32_t i) const { return cells_[i + 1] - cells_[i]; }
  uint32_t firstCell(uint32_t i) const { return cells_[i]; }

  // Continuous position in [0,1) with density pdfContinuous (func(x) / integral, to the grid's
  // cells); returns the bin in `bin`.
  float sampleContinuous(float u, float* pdf = nullptr, uint32_t* bin = nullptr) const;
  float pdfContinuous(float x) const;

 private:
  uint32_t binOf(float x) const;

  std::vector<float> func_;
  std::vector<uint32_t> cells_;  // size()+1 entries: bin i owns cells [cells_[i], cells_[i+1]); 0 and kCells
  float total_ = 0;              // sum of weights as given
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
