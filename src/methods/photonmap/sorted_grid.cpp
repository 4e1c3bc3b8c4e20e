#include "sorted_grid.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <bit>
#include <stdexcept>

#include "lucent/core/parallel.h"
#include "lucent/core/stop.h"

#include "bitonic_sort.h"

namespace lucent {
namespace {


// Sorts (key, photon index) pairs with the bitonic sort and finds the start of every key's run by
// binary search, one work item per key (Fig. 4). keys.size() photons, keyCount possible keys.
void sortAndIndex(const std::vector<uint32_t>& keys, uint32_t keyCount, std::vector<uint32_t>& photonList,
                  std::vector<uint32_t>& firstPhoton, RenderStats* stats) {
  const size_t n = keys.size();
  if (n >= UINT32_MAX) throw std::length_error("photon maps hold fewer than 2^32 - 1 photons");
  beginStage("bitonic_sort");
  Stopwatch sortClock;
  std::vector<uint64_t> sorted(n);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, kItemsPerTask), [&](const auto& r) {
    stopPoint();
    for (size_t i = r.begin(); i != r.end(); ++i) sorted[i] = packSortKey(keys[i], uint32_t(i));
  });
  bitonicSort(sorted);
  photonList.resize(n);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, kItemsPerTask), [&](const auto& r) {
    stopPoint();
    for (size_t i = r.begin(); i != r.end(); ++i) photonList[i] = sortIndexOf(sorted[i]);
  });
  if (stats) stats->addStage("bitonic_sort", sortClock.seconds());

  // The first entry whose key is >= the cell's: for an empty cell, the next cell's first photon.
  beginStage("binary_search");
  Stopwatch searchClock;
  firstPhoton.resize(size_t(keyCount) + 1);
  tbb::parallel_for(tbb::blocked_range<uint32_t>(0, keyCount + 1, kItemsPerTask), [&](const auto& r) {
    stopPoint();
    for (uint32_t c = r.begin(); c != r.end(); ++c) {
      if (c == keyCount) {
        firstPhoton[c] = uint32_t(n);
        continue;
      }
      uint32_t lo = 0, hi = uint32_t(n);
      const uint64_t target = packSortKey(c, 0);
      while (lo < hi) {
        const uint32_t mid = lo + (hi - lo) / 2;
        if (sorted[mid] < target) lo = mid + 1;
        else hi = mid;
      }
      firstPhoton[c] = lo;
    }
  });
  if (stats) stats->addStage("binary_search", searchClock.seconds());
}

}  // namespace

SortedGrid buildSortedGrid(std::vector<Photon> photons, const GridOptions& options, RenderStats* stats) {
  SortedGrid map;
  map.photons = std::move(photons);
  beginStage("grid_keys");
  Stopwatch keyClock;
  map.grid = makeUniformGrid(map.photons, options, std::min<uint64_t>(options.maxCells, UINT32_MAX - 1));
  std::vector<uint32_t> keys(map.photons.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, keys.size(), kItemsPerTask), [&](const auto& r) {
    stopPoint();
    for (size_t i = r.begin(); i != r.end(); ++i) keys[i] = map.grid.cellIndex(map.grid.cellOf(map.photons[i].position));
  });
  if (stats) stats->addStage("grid_keys", keyClock.seconds());
  sortAndIndex(keys, uint32_t(map.grid.cellCount()), map.photonList, map.firstPhoton, stats);
  beginStage("cell_counts");
  Stopwatch countClock;
  map.cellCounts = buildCellCountTable(map.grid, [&](uint32_t c) { return map.firstPhoton[c + 1] - map.firstPhoton[c]; });
  if (stats) stats->addStage("cell_counts", countClock.seconds());
  beginStage("gather_photons");
  Stopwatch gatherClock;
  map.listedPhotons = gatherPhotons(map.photons, map.photonList);
  map.columns = photonColumns(map.listedPhotons);
  if (stats) stats->addStage("gather_photons", gatherClock.seconds());
  return map;
}

HashedGrid buildHashedGrid(std::vector<Photon> photons, const GridOptions& options, RenderStats* stats) {
  HashedGrid map;
  map.photons = std::move(photons);
  const size_t n = map.photons.size();
  beginStage("grid_keys");
  Stopwatch keyClock;
  map.grid = makeUniformGrid(map.photons, options, 0);
  const double cellsFilled = std::max(1.0, double(n) / options.photonsPerCell);
  const uint64_t buckets = std::min<uint64_t>(
      std::bit_ceil(uint64_t(options.hashBuckets > 0 ? double(options.hashBuckets) : 2 * cellsFilled)), 1u << 30);
  map.bucketMask = uint32_t(buckets - 1);
  std::vector<uint32_t> keys(n);
  std::vector<uint64_t> cellKeys(n);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, kItemsPerTask), [&](const auto& r) {
    stopPoint();
    for (size_t i = r.begin(); i != r.end(); ++i) {
      cellKeys[i] = UniformGrid::cellKey(map.grid.cellOf(map.photons[i].position));
      keys[i] = map.bucketOf(cellKeys[i]);
    }
  });
  if (stats) stats->addStage("grid_keys", keyClock.seconds());
  sortAndIndex(keys, uint32_t(buckets), map.photonList, map.firstPhoton, stats);
  map.cellKeys.resize(n);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, kItemsPerTask), [&](const auto& r) {
    stopPoint();
    for (size_t i = r.begin(); i != r.end(); ++i) map.cellKeys[i] = cellKeys[map.photonList[i]];
  });
  beginStage("gather_photons");
  Stopwatch gatherClock;
  map.listedPhotons = gatherPhotons(map.photons, map.photonList);
  if (stats) stats->addStage("gather_photons", gatherClock.seconds());
  return map;
}

}  // namespace lucent
