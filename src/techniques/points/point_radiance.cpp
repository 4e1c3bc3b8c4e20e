#include "lucent/techniques/points/point_radiance.h"

#include <algorithm>
#include <stdexcept>

#include "lucent/techniques/points/bottom_up.h"
#include "lucent/techniques/points/point_hierarchy.h"

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

std::vector<DirectionalRadiance> directionalRadiance(const PointHierarchy& h, std::span<const Rgb> radiance) {
  if (radiance.size() != h.nodeCount() || h.floatNodes.size() != h.nodeCount() || h.nodeAreas.size() != h.nodeCount())
    throw std::invalid_argument("directionalRadiance: the array needs one entry per node (nodeCount())");
  std::vector<DirectionalRadiance> d(h.leafCount);
  auto add = [&](DirectionalRadiance& to, uint32_t child) {
    if (child < h.leafCount) {
      const DirectionalRadiance& c = d[child];
      for (int k = 0; k < 6; ++k) to.shown[k] += c.shown[k], to.area[k] += c.area[k];
      return;
    }
    const Vec3 n = h.floatNodes[child].cone.axis;
    const float area = h.nodeAreas[child];
    const float towards[6] = {n.x, -n.x, n.y, -n.y, n.z, -n.z};
    for (int k = 0; k < 6; ++k) {
      const float shown = area * std::max(0.0f, towards[k]);
      to.shown[k] += radiance[child] * shown;
      to.area[k] += shown;
    }
  };
  points::forEachInteriorBottomUp(h.leafCount, [&](uint32_t i) {
    DirectionalRadiance node{};
    add(node, firstChild(i));
    add(node, secondChild(i));
    d[i] = node;
  });
  return d;
}

std::vector<HalfRgb> packRadiance(std::span<const Rgb> radiance) {
  std::vector<HalfRgb> half(radiance.size());
  points::parallelFor(0, uint32_t(radiance.size()), [&](uint32_t i) { half[i] = toHalf(radiance[i]); });
  return half;
}

}  // namespace lucent
