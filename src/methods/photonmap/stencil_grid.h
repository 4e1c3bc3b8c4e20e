// The approximate grid photon map built by stencil routing (Purcell et al. 2003, section 2.2.2): a
// fixed footprint of m x m photon slots per cell; the first m^2 photons that arrive at a cell are
// stored, the rest only counted, and the stored photons' power is scaled so that the cell keeps the
// power that arrived (power redistribution).
#pragma once
#include <span>
#include <vector>

#include "lucent/core/stats.h"
#include "photon_columns.h"
#include "sorted_grid.h"
#include "uniform_grid.h"

namespace lucent {

struct StencilGrid {
  static constexpr uint32_t kEmptySlot = UINT32_MAX;

  UniformGrid grid;
  uint32_t side = 16;              // m
  std::vector<Photon> photons;     // as given; stored photons' power redistributed
  std::vector<uint32_t> slots;     // cell c's footprint: slots [c m^2, (c+1) m^2), photon indices in
                                   // arrival (= index) order, kEmptySlot after the last stored one
  std::vector<uint32_t> arrived;   // photons routed to each cell: the stencil buffer's final count
  CellCountTable cellCounts;       // stored photons per box of cells, to skip empty ones
  // What the search reads: the footprints' stored photons compacted in cell order (storedList,
  // photons[storedList[i]] in listedPhotons, cell c's from firstStored[c]), so that a row of cells
  // is one run, as in the sorted grid.
  std::vector<uint32_t> storedList, firstStored;
  std::vector<Photon> listedPhotons;
  PhotonColumns columns;  // listedPhotons as columns, for the radiance estimate
  // The stored photons again (a third copy, after `photons` and `listedPhotons`, with its own
  // photon list and columns), in a sorted grid of kSumGridSplit
  // times this grid's cells along x over the stored photons' bounds (not nested in this grid's
  // cells, and coarsened like any grid beyond maxCells): the estimate cell by cell
  // (estimate_by_cell.h) sums a sphere's photons from rows trimmed to its chords, and this grid's
  // coarse cells hold up to m^2 photons each. The search, and so the radius, stays this grid's.
  // Its build, a bitonic sort, is timed in build_map ("sum_grid"); stencil routing itself sorts
  // nothing.
  static constexpr uint32_t kSumGridSplit = 8;
  SortedGrid sumGrid;

  uint32_t capacity() const { return side * side; }
  uint32_t stored(uint32_t cell) const { return std::min(arrived[cell], capacity()); }
  CellPhotons cellPhotons(CellCoord c) const { return rowPhotons(c.x, c.x, c.y, c.z); }
  CellPhotons rowPhotons(int32_t x0, int32_t x1, int32_t y, int32_t z) const {
    return cellRangePhotons(grid.cellIndex({x0, y, z}), grid.cellIndex({x1, y, z}));
  }
  // The photons of cells firstCell..lastCell in index order, one run of the list.
  CellPhotons cellRangePhotons(uint32_t firstCell, uint32_t lastCell) const {
    return listRun(listedPhotons, storedList, columns, firstStored[firstCell], firstStored[lastCell + 1]);
  }
};

// Takes the photons by value (move them in: no copy). Stages, timed into `stats` when given: "grid_keys" (cell per photon), "stencil_count" (arrivals
// per cell), "stencil_route" (photons to their cells' footprints in arrival order, power
// redistribution), "gather_photons" (the compacted list), "sum_grid" (sumGrid). The grid has at most min(maxCells, maxStencilSlots / m^2) cells.
StencilGrid buildStencilGrid(std::vector<Photon> photons, const GridOptions& options = {},
                             RenderStats* stats = nullptr);

}  // namespace lucent
