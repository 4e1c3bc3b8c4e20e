// Grid photon maps built by sorting (Purcell et al. 2003): the sorted grid of section 2.2.1 (bitonic
// sort of photons by cell, then the first photon of every cell by binary search, Fig. 4) and the
// hashed grid of section 4.4 (the same build keyed by a hash of the cell, for mostly empty bounds).
#pragma once
#include <span>
#include <vector>

#include "lucent/core/rng.h"
#include "lucent/core/stats.h"
#include "photon_columns.h"
#include "uniform_grid.h"

namespace lucent {

struct SortedGrid {
  UniformGrid grid;
  std::vector<Photon> photons;        // as given
  std::vector<uint32_t> photonList;   // photon indices sorted by cell, then index (Fig. 4 "photon list")
  std::vector<uint32_t> firstPhoton;  // per cell, where its photons start in photonList (an empty
                                      // cell points at the next cell's first photon); one extra
                                      // entry holds the photon count (Fig. 4 "uniform grid")
  std::vector<Photon> listedPhotons;  // photons[photonList[i]]: the search reads a cell's photons in
                                      // one run instead of gathering them from all over memory
  PhotonColumns columns;              // listedPhotons as columns, for the radiance estimate
  CellCountTable cellCounts;          // photons per box of cells, to skip empty ones

  CellPhotons cellPhotons(CellCoord c) const { return rowPhotons(c.x, c.x, c.y, c.z); }
  // Cells x0..x1 of a row are consecutive keys, so their photons are one run of the list.
  CellPhotons rowPhotons(int32_t x0, int32_t x1, int32_t y, int32_t z) const {
    return cellRangePhotons(grid.cellIndex({x0, y, z}), grid.cellIndex({x1, y, z}));
  }
  // The photons of cells firstCell..lastCell in index order, one run of the list.
  CellPhotons cellRangePhotons(uint32_t firstCell, uint32_t lastCell) const {
    return listRun(listedPhotons, photonList, columns, firstPhoton[firstCell], firstPhoton[lastCell + 1]);
  }
};

// Takes the photons by value (move them in: no copy) and keeps them in their order. Stages, timed
// into `stats` when given: "grid_keys" (cell per photon), "bitonic_sort", "binary_search" (first
// photon per cell).
SortedGrid buildSortedGrid(std::vector<Photon> photons, const GridOptions& options = {},
                           RenderStats* stats = nullptr);

struct HashedGrid {
  UniformGrid grid;                   // any resolution up to 2^21 cells per axis
  std::vector<Photon> photons;        // as given
  std::vector<uint32_t> photonList;   // photon indices sorted by bucket, then index
  std::vector<uint64_t> cellKeys;     // UniformGrid::cellKey of each photonList entry
  std::vector<uint32_t> firstPhoton;  // per bucket, as SortedGrid::firstPhoton per cell
  std::vector<Photon> listedPhotons;  // photons[photonList[i]], as SortedGrid's
  uint32_t bucketMask = 0;            // buckets - 1

  uint32_t bucketOf(uint64_t cellKey) const { return uint32_t(mix64(cellKey)) & bucketMask; }
  // The whole bucket of cell c: entries of other cells in it are skipped by the search.
  CellPhotons cellPhotons(CellCoord c) const {
    const uint64_t key = UniformGrid::cellKey(c);
    const uint32_t b = bucketOf(key);
    return {listedPhotons.data() + firstPhoton[b], photonList.data() + firstPhoton[b],
            firstPhoton[b + 1] - firstPhoton[b], cellKeys.data() + firstPhoton[b], key};
  }
};

// Stages as buildSortedGrid's; the key is the cell's bucket. The grid ignores options.maxCells.
HashedGrid buildHashedGrid(std::vector<Photon> photons, const GridOptions& options = {},
                           RenderStats* stats = nullptr);

}  // namespace lucent
