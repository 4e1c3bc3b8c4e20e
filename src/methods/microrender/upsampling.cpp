#include "upsampling.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "lucent/core/stop.h"

namespace lucent {

namespace {

// Weights fall to e^-1 for a neighbour one lattice footprint off the point's tangent plane, and with
// the 16th power of the normals' cosine (0.5 at 17 degrees).
constexpr float kNormalPower = 16;
// Below this sum of weights (bilinear weights sum to 1) the point is gathered instead.
constexpr float kVanishingWeight = 0.05f;

Rgb reflectance(const ShadingPoint& p) { return layerAlbedo(p.bsdf); }

Rgb demodulate(Rgb v, Rgb rho) {
  return {rho.r > 0 ? v.r / rho.r : 0.0f, rho.g > 0 ? v.g / rho.g : 0.0f, rho.b > 0 ? v.b / rho.b : 0.0f};
}

}  // namespace

std::vector<uint32_t> upsampleIndirect(std::span<const ShadingPoint> points, const UpsamplingSettings& s,
                                       std::span<Rgb> indirect) {
  // The points of each pixel: they come grouped by pixel.
  const size_t pixels = size_t(s.width) * s.height;
  std::vector<uint32_t> first(pixels + 1, 0);
  for (const ShadingPoint& p : points) ++first[p.pixel + 1];
  for (size_t i = 0; i < pixels; ++i) first[i + 1] += first[i];
  std::vector<uint32_t> byPixel(points.size());
  {
    std::vector<uint32_t> next(first.begin(), first.end() - 1);
    for (uint32_t i = 0; i < points.size(); ++i) byPixel[next[points[i].pixel]++] = i;
  }
  std::vector<uint8_t> vanished(points.size(), 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, points.size(), 1024), [&](const tbb::blocked_range<size_t>& r) {
    stopPoint();
    for (size_t i = r.begin(); i != r.end(); ++i) {
      const ShadingPoint& q = points[i];
      if (onGatherLattice(q.pixel, s.width, s.step)) continue;
      const int x = int(q.pixel % uint32_t(s.width)), y = int(q.pixel / uint32_t(s.width));
      const int x0 = x / s.step * s.step, y0 = y / s.step * s.step;
      const float fx = float(x - x0) / float(s.step), fy = float(y - y0) / float(s.step);
      const float footprint = length(q.position - s.eye) * s.pixelAngle * float(s.step);
      float total = 0;
      Rgb sum;
      for (int corner = 0; corner < 4; ++corner) {
        const int lx = x0 + (corner & 1) * s.step, ly = y0 + (corner >> 1) * s.step;
        if (lx >= s.width || ly >= s.height) continue;
        const float bilinear = ((corner & 1) ? fx : 1 - fx) * ((corner >> 1) ? fy : 1 - fy);
        if (!(bilinear > 0)) continue;
        const uint32_t lp = uint32_t(ly) * uint32_t(s.width) + uint32_t(lx);
        for (uint32_t k = first[lp]; k < first[lp + 1]; ++k) {
          const ShadingPoint& n = points[byPixel[k]];
          if (n.sample != q.sample) continue;
          const float c = std::max(0.0f, dot(q.normal, n.normal));
          const float plane = dot(q.normal, n.position - q.position) / std::max(footprint, 1e-30f);
          const float w = bilinear * std::pow(c, kNormalPower) * std::exp(-plane * plane);
          if (!(w > 0)) continue;
          total += w;
          sum += demodulate(indirect[byPixel[k]], reflectance(n)) * w;
        }
      }
      if (total < kVanishingWeight) {
        vanished[i] = 1;
        continue;
      }
      indirect[i] = sum * reflectance(q) * (1.0f / total);
    }
  });
  std::vector<uint32_t> left;
  for (uint32_t i = 0; i < points.size(); ++i)
    if (vanished[i]) left.push_back(i);
  return left;
}

}  // namespace lucent
