#include "lucent/methods/points/point_radiance.h"

#include <stdexcept>

#include "bottom_up.h"
#include "lucent/methods/points/point_hierarchy.h"

namespace lucent {

void pullRadiance(const PointHierarchy& h, std::span<Rgb> radiance) {
  if (radiance.size() != h.nodeCount() || h.nodeAreas.size() != h.nodeCount())
    throw std::invalid_argument("pullRadiance: the array needs one entry per node (nodeCount())");
  // Radiance of a node seen as one surface: the average over its area (Section 4, "pull").
  points::forEachInteriorBottomUp(h.leafCount, [&](uint32_t i) {
    const float a = h.nodeAreas[firstChild(i)], b = h.nodeAreas[secondChild(i)];
    const Rgb la = radiance[firstChild(i)], lb = radiance[secondChild(i)];
    radiance[i] = a + b > 0 ? (la * a + lb * b) / (a + b) : (la + lb) * 0.5f;
  });
}

std::vector<HalfRgb> packRadiance(std::span<const Rgb> radiance) {
  std::vector<HalfRgb> half(radiance.size());
  points::parallelFor(0, uint32_t(radiance.size()), [&](uint32_t i) { half[i] = toHalf(radiance[i]); });
  return half;
}

}  // namespace lucent
