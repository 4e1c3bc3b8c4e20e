// Stencil routing on the CPU. On the GPU, each photon is drawn as an m x m point over its cell's
// footprint; the stencil buffer, holding 0 .. m^2-1 across the footprint and incremented by every
// draw, lets exactly one fragment through per photon, so the i-th photon to arrive lands in slot i
// and photons after the m^2-th are only counted. The rasterizer processes points in draw order,
// so "arrival" is photon index order.
//
// Here the same result comes from data-parallel stages a GPU could also run: arrivals per cell are
// counted with integer atomics (the stencil count; totals do not depend on the order), a prefix sum
// gives every cell a segment of an arrival list, photons are scattered into their segments, and one
// work item per cell puts its segment back into index order, stores the first m^2 in its footprint
// and redistributes power. Nothing depends on the thread schedule.
#include "stencil_grid.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <stdexcept>

#include "lucent/core/parallel.h"
#include "lucent/core/stop.h"

namespace lucent {
namespace {


// The scale of each stored photon's power in a cell whose arrivals, in index order, are `ids`.
Rgb redistributionScale(const std::vector<Photon>& photons, const uint32_t* ids, uint32_t arrived,
                        uint32_t stored, PowerRedistribution mode) {
  const float byCount = float(arrived) / float(stored);
  if (arrived == stored || mode == PowerRedistribution::Count) return Rgb(byCount);
  double all[3] = {0, 0, 0}, kept[3] = {0, 0, 0};
  for (uint32_t i = 0; i < arrived; ++i)
    for (int c = 0; c < 3; ++c) {
      all[c] += photons[ids[i]].power[c];
      if (i < stored) kept[c] += photons[ids[i]].power[c];
    }
  Rgb scale;
  for (int c = 0; c < 3; ++c) scale[c] = kept[c] > 0 ? float(all[c] / kept[c]) : byCount;
  return scale;
}

}  // namespace

StencilGrid buildStencilGrid(std::vector<Photon> photons, const GridOptions& options, RenderStats* stats) {
  const size_t n = photons.size();
  if (n >= UINT32_MAX) throw std::length_error("photon maps hold fewer than 2^32 - 1 photons");
  StencilGrid map;
  map.photons = std::move(photons);
  map.side = std::max(1u, options.stencilSide);
  const uint32_t capacity = map.capacity();

  beginStage("grid_keys");
  Stopwatch keyClock;
  const uint64_t maxCells = std::max<uint64_t>(1, std::min<uint64_t>(options.maxCells, options.maxStencilSlots / capacity));
  map.grid = makeUniformGrid(map.photons, options, std::min<uint64_t>(maxCells, UINT32_MAX - 1));
  const uint32_t cells = uint32_t(map.grid.cellCount());
  std::vector<uint32_t> cellOfPhoton(n);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, kItemsPerTask), [&](const auto& r) {
    stopPoint();
    for (size_t i = r.begin(); i != r.end(); ++i) cellOfPhoton[i] = map.grid.cellIndex(map.grid.cellOf(map.photons[i].position));
  });
  if (stats) stats->addStage("grid_keys", keyClock.seconds());

  beginStage("stencil_count");
  Stopwatch countClock;
  map.arrived.assign(cells, 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, kItemsPerTask), [&](const auto& r) {
    stopPoint();
    for (size_t i = r.begin(); i != r.end(); ++i)
      std::atomic_ref<uint32_t>(map.arrived[cellOfPhoton[i]]).fetch_add(1, std::memory_order_relaxed);
  });
  if (stats) stats->addStage("stencil_count", countClock.seconds());

  beginStage("stencil_route");
  Stopwatch routeClock;
  std::vector<uint32_t> offset(size_t(cells) + 1, 0);
  for (uint32_t c = 0; c < cells; ++c) offset[c + 1] = offset[c] + map.arrived[c];
  std::vector<uint32_t> cursor(offset.begin(), offset.end() - 1), arrivals(n);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, kItemsPerTask), [&](const auto& r) {
    stopPoint();
    for (size_t i = r.begin(); i != r.end(); ++i)
      arrivals[std::atomic_ref<uint32_t>(cursor[cellOfPhoton[i]]).fetch_add(1, std::memory_order_relaxed)] = uint32_t(i);
  });
  map.slots.resize(size_t(cells) * capacity);
  tbb::parallel_for(tbb::blocked_range<uint32_t>(0, cells, 64), [&](const auto& r) {
    stopPoint();
    for (uint32_t c = r.begin(); c != r.end(); ++c) {
      uint32_t* ids = arrivals.data() + offset[c];
      const uint32_t arrived = map.arrived[c], stored = std::min(arrived, capacity);
      std::sort(ids, ids + arrived);  // arrival order
      uint32_t* footprint = map.slots.data() + size_t(c) * capacity;
      std::copy(ids, ids + stored, footprint);
      std::fill(footprint + stored, footprint + capacity, StencilGrid::kEmptySlot);
      if (arrived > stored) {
        const Rgb scale = redistributionScale(map.photons, ids, arrived, stored, options.redistribution);
        for (uint32_t i = 0; i < stored; ++i) map.photons[ids[i]].power *= scale;
      }
    }
  });
  if (stats) stats->addStage("stencil_route", routeClock.seconds());
  beginStage("cell_counts");
  Stopwatch cellCountClock;
  map.cellCounts = buildCellCountTable(map.grid, [&](uint32_t c) { return map.stored(c); });
  if (stats) stats->addStage("cell_counts", cellCountClock.seconds());
  beginStage("gather_photons");
  Stopwatch gatherClock;
  map.firstStored.assign(size_t(cells) + 1, 0);
  for (uint32_t c = 0; c < cells; ++c) map.firstStored[c + 1] = map.firstStored[c] + map.stored(c);
  map.storedList.resize(map.firstStored[cells]);
  tbb::parallel_for(tbb::blocked_range<uint32_t>(0, cells, 256), [&](const auto& r) {
    stopPoint();
    for (uint32_t c = r.begin(); c != r.end(); ++c)
      std::copy_n(map.slots.data() + size_t(c) * capacity, map.stored(c), map.storedList.data() + map.firstStored[c]);
  });
  map.listedPhotons = gatherPhotons(map.photons, map.storedList);
  map.columns = photonColumns(map.listedPhotons);
  if (stats) stats->addStage("gather_photons", gatherClock.seconds());
  beginStage("sum_grid");
  Stopwatch sumGridClock;
  GridOptions sumOptions = options;
  sumOptions.resolution = {uint32_t(map.grid.res[0]) * StencilGrid::kSumGridSplit, uint32_t(map.grid.res[1]),
                           uint32_t(map.grid.res[2])};
  map.sumGrid = buildSortedGrid(map.listedPhotons, sumOptions);
  if (stats) stats->addStage("sum_grid", sumGridClock.seconds());
  return map;
}

}  // namespace lucent
