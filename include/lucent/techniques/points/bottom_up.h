// Interior nodes of the point hierarchy level by level from the leaves up (2.1, "successively merging
// two nodes at a time"): one work item per node, levels in sequence, so each node reads finished
// children. O(n) in all.
#pragma once
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstdint>

#include "lucent/core/stop.h"
#include "lucent/techniques/points/node_tree.h"

namespace lucent::points {

inline constexpr uint32_t kNodeGrain = 4096;

// f(node) for every interior node, deepest level first.
template <class F>
void forEachInteriorBottomUp(uint32_t leafCount, F&& f) {
  for (uint32_t first = leafCount >> 1; first >= kRootNode; first >>= 1) {
    const uint32_t end = 2 * first;
    if (end - first < kNodeGrain) {
      for (uint32_t i = first; i < end; ++i) f(i);
      continue;
    }
    tbb::parallel_for(tbb::blocked_range<uint32_t>(first, end, kNodeGrain), [&](const auto& r) {
      stopPoint();
      for (uint32_t i = r.begin(); i != r.end(); ++i) f(i);
    });
  }
}

// f(i) for i in [begin, end), in parallel.
template <class F>
void parallelFor(uint32_t begin, uint32_t end, F&& f) {
  tbb::parallel_for(tbb::blocked_range<uint32_t>(begin, end, kNodeGrain), [&](const auto& r) {
    stopPoint();
    for (uint32_t i = r.begin(); i != r.end(); ++i) f(i);
  });
}

}  // namespace lucent::points
