// The uniform grid over the photons' bounds that Purcell et al. 2003 store photons in (section 2.2),
// and the small interface through which the kNN-grid search (knn_grid.h) reads any grid photon map.
#pragma once
#include <array>
#include <concepts>
#include <cstdint>
#include <functional>
#include <span>
#include <type_traits>
#include <vector>

#include "lucent/core/math.h"
#include "lucent/methods/photonmap_records.h"
#include "lucent/techniques/photons/photon.h"

namespace lucent {

// How the resolution is chosen, first match wins:
//  - `resolution`: cells per axis as given (the paper's 250x1x250 and 25x25x50); cells may be boxes;
//  - `cellSize` > 0: cubic cells of that side, e.g. the maximum search radius, so that a kNN-grid
//    search ends within the first shell or two (Wald et al. 2002 use twice the fixed radius);
//  - otherwise cubic cells sized so that the bounding box holds about photons / photonsPerCell
//    cells; axes thinner than a cell (photons on a floor) get one cell and the cells are sized over
//    the others.
// Dense grids are coarsened until they have at most maxCells cells (their memory); the hashed grid
// ignores maxCells, as memory does not grow with its resolution.
enum class PowerRedistribution : uint8_t {
  Count,  // the paper's: stored photons' power times arrived / stored (exact for equal-power photons)
  Power,  // per RGB channel, times (power arrived) / (power stored): exact for any photon powers
};

struct GridOptions {
  std::array<uint32_t, 3> resolution{0, 0, 0};
  float cellSize = 0;
  float photonsPerCell = 8;
  uint64_t maxCells = uint64_t(1) << 24;
  // Stencil grid (section 2.2.2): m, the side of a cell's m x m footprint, and a bound on the
  // footprints' total slots (the paper's stencil buffer was 1024 x 1024).
  uint32_t stencilSide = 16;
  uint64_t maxStencilSlots = uint64_t(1) << 20;
  PowerRedistribution redistribution = PowerRedistribution::Count;
  // Hashed grid (section 4.4): buckets, rounded up to a power of two; 0: twice the cells that
  // photons / photonsPerCell would fill.
  uint32_t hashBuckets = 0;
};

// Bounds the photons (a parallel min/max reduction) and sizes the grid by `options`, with at most
// maxCells cells (0: no bound but the 21 bits per axis of packed cell keys).
UniformGrid makeUniformGrid(std::span<const Photon> photons, const GridOptions& options, uint64_t maxCells);

// Photons per box of cells in O(1): a 3-D summed-area table (prefix sums of the cells' photon
// counts along x, y and z). The kNN-grid search skips the shells and rows of cells it shows empty,
// so queries in dark regions, which would otherwise visit every cell out to the maximum radius
// (Purcell et al. 2003, 3.1), cost a few lookups per shell. A GPU builds it with three passes of
// prefix sums.
struct CellCountTable {
  std::array<int32_t, 3> res{0, 0, 0};
  std::vector<uint32_t> prefix;  // (res + 1) per axis; entry (x, y, z): photons in cells < (x, y, z)

  // Photons in the cells [lo, hi] (inclusive); 0 for an empty box.
  uint32_t count(const int32_t lo[3], const int32_t hi[3]) const {
    if (lo[0] > hi[0] || lo[1] > hi[1] || lo[2] > hi[2]) return 0;
    const size_t sx = 1, sy = size_t(res[0]) + 1, sz = sy * (size_t(res[1]) + 1);
    const size_t x0 = size_t(lo[0]) * sx, x1 = size_t(hi[0] + 1) * sx;
    const size_t y0 = size_t(lo[1]) * sy, y1 = size_t(hi[1] + 1) * sy;
    const size_t z0 = size_t(lo[2]) * sz, z1 = size_t(hi[2] + 1) * sz;
    const uint32_t* p = prefix.data();
    // Inclusion-exclusion over the box's eight corners; unsigned wrap-around cancels exactly.
    return p[x1 + y1 + z1] - p[x0 + y1 + z1] - p[x1 + y0 + z1] - p[x1 + y1 + z0] + p[x0 + y0 + z1] +
           p[x0 + y1 + z0] + p[x1 + y0 + z0] - p[x0 + y0 + z0];
  }
};

// The table for `grid` from each cell's photon count, cellCount(cellIndex).
CellCountTable buildCellCountTable(const UniformGrid& grid, const std::function<uint32_t(uint32_t)>& cellCount);

// photons[ids[i]] for every i: a map's photons in the order the search reads them (one parallel
// gather, as a GPU would copy them into list order).
std::vector<Photon> gatherPhotons(const std::vector<Photon>& photons, const std::vector<uint32_t>& ids);

struct PhotonColumns;

// The photons of one cell, or of a run of cells that the map keeps contiguous (a row, a range of
// cell indices), as a grid photon map hands them to the kNN-grid search.
struct CellPhotons {
  const Photon* photons = nullptr;     // the photons, contiguous: read without indirection
  const uint32_t* ids = nullptr;       // their indices into the map's photons
  uint32_t count = 0;
  const uint64_t* cellKeys = nullptr;  // hashed grid only: each entry's cell, as entries of other
  uint64_t cellKey = 0;                // cells share the bucket and must be skipped (section 4.4)
  const PhotonColumns* columns = nullptr;  // sorted and stencil grids: the same photons as columns,
  uint32_t first = 0;                      // from entry `first` on (photon_columns.h)
};

// List entries [first, end) of a map that keeps its photons in search order (listed) and as columns.
inline CellPhotons listRun(const std::vector<Photon>& listed, const std::vector<uint32_t>& ids,
                           const PhotonColumns& columns, uint32_t first, uint32_t end) {
  CellPhotons run{listed.data() + first, ids.data() + first, end - first};
  run.columns = &columns, run.first = first;
  return run;
}

// What the kNN-grid search needs of a map: its grid, its photons, and the photons of a cell; a map
// with a dense grid also has the CellCountTable `cellCounts` (the hashed grid has none).
template <class Map>
concept GridPhotonMap = requires(const Map& map, CellCoord c) {
  { map.grid } -> std::convertible_to<UniformGrid>;
  { map.photons.data() } -> std::convertible_to<const Photon*>;
  { map.cellPhotons(c) } -> std::same_as<CellPhotons>;
};

}  // namespace lucent
