#include "methods/envpbgi/visible_points.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>

#include "lucent/core/parallel.h"
#include "lucent/core/stop.h"
#include "lucent/techniques/microbuffers/micro_buffer.h"
#include "lucent/techniques/points/bottom_up.h"
#include "lucent/techniques/points/node_tree.h"

namespace lucent {

namespace {

uint32_t& selectionOf(EnvHierarchy& h, uint32_t node) { return h.nodes[node].selection; }
bool has(const EnvHierarchy& h, uint32_t node, uint32_t bits) { return (h.nodes[node].selection & bits) != 0; }

}  // namespace

CameraDepth traceCameraDepth(const Scene& scene, const Visibility& vis) {
  CameraDepth d;
  d.width = scene.camera.width;
  d.height = scene.camera.height;
  const PinholeCamera camera(scene.camera);
  d.depth.resize(size_t(d.width) * size_t(d.height));
  // Rows in packets of 16 pixels.
  const int packetsPerRow = (d.width + kWidestPacket - 1) / kWidestPacket;
  tbb::parallel_for(tbb::blocked_range<int>(0, d.height * packetsPerRow, 16), [&](const tbb::blocked_range<int>& r) {
    stopPoint();
    for (int p = r.begin(); p != r.end(); ++p) {
      const int y = p / packetsPerRow, x0 = (p % packetsPerRow) * kWidestPacket;
      const int count = std::min(kWidestPacket, d.width - x0);
      Ray rays[kWidestPacket];
      for (int j = 0; j < count; ++j) rays[j] = camera.generate(float(x0 + j) + 0.5f, float(y) + 0.5f);
      Hit hits[kWidestPacket];
      intersectPacket<kWidestPacket>(vis, count, [&](int j) { return rays[j]; }, hits, RayKind::Camera);
      for (int j = 0; j < count; ++j) d.depth[size_t(y) * size_t(d.width) + size_t(x0 + j)] = hits[j].t;
    }
  });
  return d;
}

std::vector<uint32_t> selectPrimaryPoints(EnvHierarchy& h, const Camera& cameraSettings, const CameraDepth& depth,
                                          const PrimarySelection& selection) {
  const PinholeCamera camera(cameraSettings);
  const uint32_t n = h.leafCount();
  const Vec3 eye = cameraSettings.eye;
  auto passes = [&](uint32_t i) {
    const EnvPointNode& node = h.nodes[i];
    const float d = length(node.position - eye);
    if (!(d > node.radius)) return false;  // the eye inside the sphere: as large as can be
    const float solidAngle = kPi * node.radius * node.radius / (d * d);
    return solidAngle < selection.maxSolidAngle && node.coneAngle < selection.maxConeAngle &&
           selection.thickness[i] <= selection.maxThickness * node.radius;
  };
  const float pixelAngle = camera.pixelAngle();
  auto visible = [&](uint32_t i) {
    const EnvPointNode& node = h.nodes[i];
    const Vec3 p = camera.project(node.position);
    if (!(p.z > 0)) return false;
    // The sphere's image: a disc about the centre's, clipped to the image, sampled by up to 8 x 8
    // pixels.
    const float reach = std::min(node.radius / (p.z * pixelAngle), 1e6f) + 0.5f;
    const float x0 = std::max(p.x - reach, 0.0f), x1 = std::min(p.x + reach, float(depth.width) - 1e-3f);
    const float y0 = std::max(p.y - reach, 0.0f), y1 = std::min(p.y + reach, float(depth.height) - 1e-3f);
    if (!(x0 <= x1 && y0 <= y1)) return false;
    const float stride = std::max(1.0f, std::max(x1 - x0, y1 - y0) / 8.0f);
    for (float y = y0; y <= y1; y += stride)
      for (float x = x0; x <= x1; x += stride) {
        const int px = int(x), py = int(y);
        const float t = depth.depth[size_t(py) * size_t(depth.width) + size_t(px)];
        if (!(t < kInf)) continue;
        const Ray ray = camera.generate(float(px) + 0.5f, float(py) + 0.5f);
        // Within the sphere and the slab of the node's leaves about its plane: a sphere reaches far
        // off a flat node's surface (a node of the ground outside a box holds points of the floor
        // inside in its sphere).
        const float grown = t * pixelAngle * stride;
        const Vec3 hit = ray.origin + ray.direction * t - node.position;
        const float reachSphere = node.radius + grown, reachSlab = selection.thickness[i] + grown;
        if (dot(hit, hit) <= reachSphere * reachSphere && std::abs(dot(hit, node.normal)) <= reachSlab) return true;
      }
    return false;
  };
  // Per node: 1 once an ancestor (or the node) passed. Levels from the root down.
  std::vector<uint8_t> passedAbove(size_t(2) * n, 0);
  std::vector<uint8_t> onCut(size_t(2) * n, 0);
  for (uint32_t first = kRootNode; first < 2 * n; first <<= 1)
    points::parallelFor(first, 2 * first, [&](uint32_t i) {
      const bool above = i != kRootNode && passedAbove[parentNode(i)];
      const bool own = !above && passes(i);
      passedAbove[i] = above || own;
      onCut[i] = !above && (own || isLeafNode(i, n)) && visible(i);
    });
  std::vector<uint32_t> primary;
  for (uint32_t i = kRootNode; i < 2 * n; ++i)
    if (onCut[i]) {
      primary.push_back(i);
      selectionOf(h, i) |= kPrimary;
    }
  return primary;
}

void markSecondaryPoints(EnvHierarchy& h, std::span<const uint32_t> texels) {
  tbb::parallel_for(tbb::blocked_range<size_t>(0, texels.size(), kItemsPerTask), [&](const tbb::blocked_range<size_t>& r) {
    stopPoint();
    for (size_t t = r.begin(); t != r.end(); ++t)
      if (microPixelShowsNode(texels[t]))
        std::atomic_ref<uint32_t>(selectionOf(h, microPixelNode(texels[t]))).fetch_or(kSecondary, std::memory_order_relaxed);
  });
}

SelectionCounts selectDirectLightPoints(EnvHierarchy& h, std::span<const uint32_t> primary, bool primarySources) {
  const uint32_t n = h.leafCount();
  const uint32_t sourceBits = primarySources ? kSecondary | kPrimary : kSecondary;
  for (EnvPointNode& node : h.nodes) node.selection &= kPrimary | kSecondary;
  // Upward: the leaves' work items climb; the second to reach a node decides it.
  std::vector<uint32_t> arrivals(size_t(2) * n, 0);
  points::parallelFor(n, 2 * n, [&](uint32_t leaf) {
    if (has(h, leaf, sourceBits)) selectionOf(h, leaf) |= kCovered;
    for (uint32_t i = leaf; i != kRootNode;) {
      const uint32_t p = parentNode(i);
      // acq_rel: the second arrival sees the first one's writes to its node.
      if (std::atomic_ref<uint32_t>(arrivals[p]).fetch_add(1, std::memory_order_acq_rel) == 0) break;
      const bool children = has(h, firstChild(p), kCovered) && has(h, secondChild(p), kCovered);
      uint32_t bits = 0;
      if (has(h, p, sourceBits) || children) bits |= kCovered;
      if (has(h, p, kSecondary) && children) bits |= kDerivable;
      selectionOf(h, p) |= bits;
      i = p;
    }
  });
  // Downward: the primary points' subtrees are disjoint (they form a cut), one work item each.
  tbb::parallel_for(tbb::blocked_range<size_t>(0, primary.size(), 1), [&](const tbb::blocked_range<size_t>& r) {
    stopPoint();
    for (size_t k = r.begin(); k != r.end(); ++k)
      for (uint32_t first = firstChild(primary[k]), end = first + 2; first < 2 * n; first <<= 1, end <<= 1)
        for (uint32_t i = first; i < end; ++i)
          if (has(h, i, kSecondary)) selectionOf(h, i) |= kUnderPrimary;
  });
  SelectionCounts c;
  c.primary = primary.size();
  for (uint32_t i = kRootNode; i < 2 * n; ++i) {
    if (!has(h, i, kSecondary)) continue;
    ++c.secondary;
    if (has(h, i, kDerivable)) continue;
    ++c.afterUpward;
    if (has(h, i, kUnderPrimary)) continue;
    ++c.afterDownward;
    if (has(h, i, kPrimary)) continue;
    ++c.ownBuffers;
    selectionOf(h, i) |= kOwnBuffer;
  }
  return c;
}

}  // namespace lucent
