// Jensen's balanced kd-tree photon map (Jensen 2001, chapter 6; Bentley 1975): the software
// reference Purcell et al. 2003 compare their grids against.
//
// The tree is implicit: photons are stored in median order, so the subtree over the range [lo, hi)
// has its splitting photon at mid = lo + (hi - lo) / 2, the left subtree at [lo, mid) and the right
// at [mid + 1, hi). The split axis sits in the photon's flags (photonSplitAxis). No pointers.
#pragma once
#include <span>
#include <string>
#include <vector>

#include "lucent/core/stats.h"
#include "lucent/techniques/photons/photon.h"

namespace lucent {

struct PhotonKdTree {
  std::vector<Photon> photons;         // median order
  std::vector<uint32_t> sourceIndex;   // the input index of each photon
};

// O(n log n): median splits along the axis of largest extent of each range's bounds, found by
// std::nth_element; one stage per tree level, a parallel_for over that level's ranges, then one
// work item per remaining small subtree. Timed into `stats` as "kdtree_build" when given.
PhotonKdTree buildPhotonKdTree(std::span<const Photon> photons, RenderStats* stats = nullptr);

struct PhotonDistance {
  float d2;        // squared distance to the query
  uint32_t index;  // into PhotonKdTree::photons
};
static_assert(sizeof(PhotonDistance) == 8);

struct KdTreeResult {
  uint32_t found = 0;   // photons in the heap, at most k
  float radius2 = 0;    // the k-th nearest's squared distance when k were found, else maxRadius^2
                        // (the searched sphere: Jensen's convention)
  uint32_t nodesVisited = 0;
};

// Dumps (docs/dump-format.md) into `directory`: <prefix>.photons and <prefix>.source_index.
void dumpPhotonKdTree(const std::string& directory, const std::string& prefix, const PhotonKdTree& tree);

// The k nearest photons within maxRadius (squared distance <= maxRadius^2), into heap[0 .. found):
// a max-heap on d2 once k were found (heap[0] the farthest), in visiting order before. `heap` holds
// at least k entries and is the caller's, so that a query allocates nothing.
KdTreeResult kdTreeNearest(const PhotonKdTree& tree, Vec3 position, uint32_t k, float maxRadius,
                           PhotonDistance* heap);

}  // namespace lucent
