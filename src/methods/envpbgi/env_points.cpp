#include "methods/envpbgi/env_points.h"

#include <stdexcept>

#include "lucent/techniques/points/bottom_up.h"
#include "lucent/techniques/points/node_tree.h"

namespace lucent {

EnvHierarchy makeEnvHierarchy(PointHierarchy points) {
  if (points.floatNodes.size() != size_t(points.nodeCount()))
    throw std::logic_error("the environment-lighting hierarchy needs float nodes");
  EnvHierarchy h;
  h.points = std::move(points);
  const uint32_t n = h.points.leafCount;
  h.nodes.assign(size_t(2) * n, EnvPointNode{});
  h.surfels.assign(size_t(2) * n, Surfel{});
  points::parallelFor(kRootNode, 2 * n, [&](uint32_t i) {
    const FloatNode& f = h.points.floatNodes[i];
    EnvPointNode& node = h.nodes[i];
    node.position = f.sphere.center;
    node.radius = f.sphere.radius;
    node.normal = f.cone.axis;
    node.coneAngle = f.cone.angle;
    if (!isLeafNode(i, n)) node.child[0] = firstChild(i), node.child[1] = secondChild(i);
    node.skip = nextNodeSkippingSubtree(i);
  });
  // Surfels: the leaves' discs, then area-weighted means from the leaves up.
  points::parallelFor(n, 2 * n, [&](uint32_t i) {
    h.surfels[i] = {h.points.floatNodes[i].sphere.center, h.points.floatNodes[i].cone.axis};
  });
  std::vector<Vec3> weightedNormal(size_t(2) * n);
  points::parallelFor(n, 2 * n, [&](uint32_t i) { weightedNormal[i] = h.surfels[i].normal * h.points.nodeAreas[i]; });
  points::forEachInteriorBottomUp(n, [&](uint32_t i) {
    const uint32_t a = firstChild(i), b = secondChild(i);
    const float wa = h.points.nodeAreas[a], wb = h.points.nodeAreas[b], w = wa + wb;
    const Vec3 position = w > 0 ? (h.surfels[a].position * wa + h.surfels[b].position * wb) / w
                                : (h.surfels[a].position + h.surfels[b].position) * 0.5f;
    weightedNormal[i] = weightedNormal[a] + weightedNormal[b];
    const float length2 = dot(weightedNormal[i], weightedNormal[i]);
    const Vec3 normal = length2 > 1e-12f * w * w ? weightedNormal[i] / std::sqrt(length2) : h.nodes[i].normal;
    h.surfels[i] = {position, normal};
  });
  return h;
}

}  // namespace lucent
