// The records of the photon map methods' stage dumps (docs/dump-format.md) that another backend reads
// beside the photons (lucent/techniques/photons/photon.h): the uniform grid over the photons' bounds
// (Purcell et al. 2003, section 2.2) and its cells.
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <type_traits>

#include "lucent/core/math.h"

namespace lucent {

struct CellCoord {
  int32_t x = 0, y = 0, z = 0;
};
static_assert(sizeof(CellCoord) == 12);

struct UniformGrid {
  Vec3 lo;              // corner of cell (0, 0, 0): the photons' lower bound
  Vec3 hi;              // the photons' upper bound (the last cell reaches beyond it on an axis
                        // that the photons do not span, such as the y of a floor's 250 x 1 x 250);
                        // the search relies on it (acceptedCube): grids come from makeUniformGrid
  Vec3 cellSize;        // per axis
  Vec3 invCellSize;
  std::array<int32_t, 3> res{1, 1, 1};
  float slack = 0;      // distance by which float rounding may put a photon outside its cell's box

  static constexpr int32_t kMaxResolution = 1 << 21;  // 21 bits per axis in packed cell keys

  uint64_t cellCount() const { return uint64_t(res[0]) * uint64_t(res[1]) * uint64_t(res[2]); }
  // The cell containing p; points outside the grid go to the nearest cell.
  CellCoord cellOf(Vec3 p) const {
    auto axis = [&](int a) {
      const float f = std::floor((p[a] - lo[a]) * invCellSize[a]);
      return f < 0 ? 0 : (f >= float(res[a]) ? res[a] - 1 : int32_t(f));
    };
    return {axis(0), axis(1), axis(2)};
  }
  uint32_t cellIndex(CellCoord c) const { return uint32_t(c.x + res[0] * (c.y + res[1] * c.z)); }
  // Unique key for any resolution, for the hashed grid.
  static uint64_t cellKey(CellCoord c) {
    return uint64_t(c.x) | uint64_t(c.y) << 21 | uint64_t(c.z) << 42;
  }
  // Where cell i begins along axis a (i may be past the last cell: where the grid's cells end).
  float cellLo(int a, int32_t i) const { return lo[a] + float(i) * cellSize[a]; }
  // Distance along axis a from coordinate x to cell i's slab, less `slack` (never more than the
  // truth), 0 inside.
  float axisGap(int a, int32_t i, float x) const {
    const float cellLo = this->cellLo(a, i), cellHi = cellLo + cellSize[a];
    return std::max(std::max(cellLo - x, x - cellHi) - slack, 0.0f);
  }
  // Squared distance from p to the box of cell c, shrunk by `slack` (never more than the truth).
  float cellDistance2(Vec3 p, CellCoord c) const {
    const float gx = axisGap(0, c.x, p.x), gy = axisGap(1, c.y, p.y), gz = axisGap(2, c.z, p.z);
    return gx * gx + gy * gy + gz * gz;
  }
};
static_assert(sizeof(UniformGrid) == 64 && std::is_trivially_copyable_v<UniformGrid>, "dumped as one record");

}  // namespace lucent
