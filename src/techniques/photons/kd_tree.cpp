#include "lucent/core/parallel.h"
#include "lucent/techniques/photons/kd_tree.h"

#include "lucent/core/dump.h"
#include "lucent/core/stop.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <numeric>
#include <stdexcept>

namespace lucent {
namespace {

struct Range {
  uint32_t lo, hi;
};

// Ranges at most this long are built whole by one work item.
constexpr uint32_t kSubtreeItem = 2048;

// Splits [lo, hi) of `order` at its median along the axis of largest extent and records the axis.
// Ties along the axis are broken by index, so the tree is unique.
void splitRange(std::span<const Photon> photons, std::vector<uint32_t>& order, std::vector<uint8_t>& axis,
                Range r) {
  Bounds3 b;
  for (uint32_t i = r.lo; i < r.hi; ++i) b.extend(photons[order[i]].position);
  const Vec3 e = b.extent();
  const int a = e.x >= e.y && e.x >= e.z ? 0 : (e.y >= e.z ? 1 : 2);
  const uint32_t mid = r.lo + (r.hi - r.lo) / 2;
  std::nth_element(order.begin() + r.lo, order.begin() + mid, order.begin() + r.hi, [&](uint32_t i, uint32_t j) {
    const float pi = photons[i].position[a], pj = photons[j].position[a];
    return pi < pj || (pi == pj && i < j);
  });
  axis[mid] = uint8_t(a);
}

void buildSubtree(std::span<const Photon> photons, std::vector<uint32_t>& order, std::vector<uint8_t>& axis,
                  Range r) {
  if (r.hi - r.lo < 2) return;
  splitRange(photons, order, axis, r);
  const uint32_t mid = r.lo + (r.hi - r.lo) / 2;
  buildSubtree(photons, order, axis, {r.lo, mid});
  buildSubtree(photons, order, axis, {mid + 1, r.hi});
}

struct Query {
  const Photon* photons;
  Vec3 p;
  uint32_t k;
  PhotonDistance* heap;
  uint32_t found = 0;
  float r2;  // acceptance radius: maxRadius^2, then the heap's farthest once full
  uint32_t visited = 0;

  static bool closer(const PhotonDistance& a, const PhotonDistance& b) { return a.d2 < b.d2; }

  void consider(uint32_t i) {
    const float d2 = distance2(photons[i].position, p);
    if (found < k) {
      if (d2 > r2) return;
      heap[found++] = {d2, i};
      if (found == k) {  // full: from now on replace the farthest (Jensen's lazy heap)
        std::make_heap(heap, heap + k, closer);
        r2 = heap[0].d2;
      }
    } else if (d2 < r2) {
      std::pop_heap(heap, heap + k, closer);
      heap[k - 1] = {d2, i};
      std::push_heap(heap, heap + k, closer);
      r2 = heap[0].d2;
    }
  }

  void locate(uint32_t lo, uint32_t hi) {
    if (lo >= hi) return;
    ++visited;
    const uint32_t mid = lo + (hi - lo) / 2;
    if (hi - lo > 1) {
      const Photon& split = photons[mid];
      const int a = photonSplitAxis(split);
      const float delta = p[a] - split.position[a];
      // The near side first, so that the radius shrinks before the far side is tested.
      if (delta < 0) {
        locate(lo, mid);
        if (delta * delta <= r2) locate(mid + 1, hi);
      } else {
        locate(mid + 1, hi);
        if (delta * delta <= r2) locate(lo, mid);
      }
    }
    consider(mid);
  }
};

}  // namespace

PhotonKdTree buildPhotonKdTree(std::span<const Photon> photons, RenderStats* stats) {
  if (photons.size() >= UINT32_MAX) throw std::length_error("photon maps hold fewer than 2^32 - 1 photons");
  beginStage("kdtree_build");
  Stopwatch clock;
  const uint32_t n = uint32_t(photons.size());
  std::vector<uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  std::vector<uint8_t> axis(n, 0);

  // Upper levels breadth first: one stage per level, its ranges in parallel.
  std::vector<Range> level, next, small;
  if (n >= 2) level.push_back({0, n});
  while (!level.empty()) {
    tbb::parallel_for(size_t(0), level.size(), [&](size_t i) {
      stopPoint();
      splitRange(photons, order, axis, level[i]);
    });
    next.clear();
    for (const Range& r : level) {
      const uint32_t mid = r.lo + (r.hi - r.lo) / 2;
      for (Range child : {Range{r.lo, mid}, Range{mid + 1, r.hi}})
        if (child.hi - child.lo >= 2) (child.hi - child.lo > kSubtreeItem ? next : small).push_back(child);
    }
    std::swap(level, next);
  }
  tbb::parallel_for(size_t(0), small.size(), [&](size_t i) {
    stopPoint();
    buildSubtree(photons, order, axis, small[i]);
  });

  PhotonKdTree tree;
  tree.photons.resize(n);
  tree.sourceIndex = std::move(order);
  tbb::parallel_for(tbb::blocked_range<uint32_t>(0, n, kItemsPerTask), [&](const auto& r) {
    stopPoint();
    for (uint32_t i = r.begin(); i != r.end(); ++i) {
      Photon p = photons[tree.sourceIndex[i]];
      p.flags = (p.flags & ~kPhotonAxisMask) | uint32_t(axis[i]) << kPhotonAxisShift;
      tree.photons[i] = p;
    }
  });
  if (stats) stats->addStage("kdtree_build", clock.seconds());
  return tree;
}

void dumpPhotonKdTree(const std::string& directory, const std::string& prefix, const PhotonKdTree& tree) {
  writeDump(directory, prefix + ".photons", "Photon", std::span(tree.photons));
  writeDump(directory, prefix + ".source_index", "uint32", std::span(tree.sourceIndex));
}

KdTreeResult kdTreeNearest(const PhotonKdTree& tree, Vec3 position, uint32_t k, float maxRadius,
                           PhotonDistance* heap) {
  KdTreeResult result;
  if (k == 0) return result;
  Query q{tree.photons.data(), position, k, heap, 0, maxRadius * maxRadius};
  q.locate(0, uint32_t(tree.photons.size()));
  result.found = q.found;
  result.radius2 = q.found == k ? q.r2 : maxRadius * maxRadius;
  result.nodesVisited = q.visited;
  return result;
}

}  // namespace lucent
