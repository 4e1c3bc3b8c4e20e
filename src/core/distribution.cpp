#include "lucent/core/distribution.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace lucent {

Distribution1D::Distribution1D(std::span<const float> weights, std::span<const uint8_t> ownCell)
    : func_(weights.begin(), weights.end()) {
  if (func_.empty()) throw std::invalid_argument("Distribution1D: no weights");
  if (!ownCell.empty() && ownCell.size() != func_.size())
    throw std::invalid_argument("Distribution1D: one own-cell flag per weight");
  std::vector<double> sums(func_.size() + 1, 0.0);
  uint64_t owners = 0;
  for (size_t i = 0; i < func_.size(); ++i) {
    if (!(func_[i] >= 0) || !std::isfinite(func_[i]))
      throw std::invalid_argument("Distribution1D: negative or non-finite weight");
    sums[i + 1] = sums[i] + func_[i];
    owners += !ownCell.empty() && ownCell[i] && func_[i] > 0;
  }
  if (owners > kCells) throw std::invalid_argument("Distribution1D: more bins that need a cell than cells");
  const double sum = sums.back();
  total_ = static_cast<float>(sum);
  cells_.resize(func_.size() + 1);
  if (sum == 0) {
    for (size_t i = 0; i <= func_.size(); ++i) cells_[i] = uint32_t(std::ceil(double(i) * kCells / func_.size()));
    return;
  }
  uint32_t ownersBefore = 0;
  for (size_t i = 0; i <= func_.size(); ++i) {
    cells_[i] = sharedCell(sums[i], sum, ownersBefore, uint32_t(owners), kCells);
    if (i < func_.size()) ownersBefore += !ownCell.empty() && ownCell[i] && func_[i] > 0;
  }
  cells_.back() = kCells;
}

uint32_t Distribution1D::sampleDiscrete(float u, float* pmfOut, float* remapped) const {
  const uint32_t i = pick(u);
  if (pmfOut) *pmfOut = pmf(i);
  if (remapped) *remapped = remap(i, u);
  return i;
}

float Distribution1D::sampleContinuous(float u, float* pdfOut, uint32_t* bin) const {
  float offset;
  const uint32_t i = sampleDiscrete(u, nullptr, &offset);
  // Rounding in (i + offset) / size() can carry x into a neighbouring bin, possibly one of zero weight:
  // nudge it back so that x, `bin` and pdfContinuous(x) agree.
  float x = std::min((i + offset) / size(), 0x1.fffffep-1f);
  while (binOf(x) > i) x = std::nextafter(x, 0.0f);
  while (binOf(x) < i) x = std::nextafter(x, 1.0f);
  if (bin) *bin = i;
  if (pdfOut) *pdfOut = pdfContinuous(x);
  return x;
}

uint32_t Distribution1D::binOf(float x) const { return std::min(static_cast<uint32_t>(x * size()), size() - 1); }

float Distribution1D::pdfContinuous(float x) const { return pmf(binOf(x)) * float(size()); }

Distribution2D::Distribution2D(std::span<const float> weights, uint32_t nu, uint32_t nv) : nu_(nu), nv_(nv) {
  if (weights.size() != size_t(nu) * nv) throw std::invalid_argument("Distribution2D: size mismatch");
  std::vector<float> rowSums(nv);
  conditional_.reserve(nv);
  for (uint32_t v = 0; v < nv; ++v) {
    conditional_.emplace_back(weights.subspan(size_t(v) * nu, nu));
    rowSums[v] = conditional_.back().total();
  }
  marginal_ = Distribution1D(rowSums);
}

Vec2 Distribution2D::sample(Vec2 u, float* pdfOut) const {
  float pdfV, pdfU;
  uint32_t row;
  const float v = marginal_.sampleContinuous(u.y, &pdfV, &row);
  const float x = conditional_[row].sampleContinuous(u.x, &pdfU);
  if (pdfOut) *pdfOut = pdfU * pdfV;
  return {x, v};
}

float Distribution2D::pdf(Vec2 uv) const {
  const auto row = std::min(static_cast<uint32_t>(uv.y * nv_), nv_ - 1);
  return marginal_.pdfContinuous(uv.y) * conditional_[row].pdfContinuous(uv.x);
}

}  // namespace lucent
