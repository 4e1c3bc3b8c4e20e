#include "uniform_grid.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <cmath>

#include "lucent/core/parallel.h"
#include "lucent/core/stop.h"

namespace lucent {
namespace {

Bounds3 photonBounds(std::span<const Photon> photons) {
  return tbb::parallel_reduce(
      tbb::blocked_range<size_t>(0, photons.size(), kItemsPerTask), Bounds3{},
      [&](const auto& r, Bounds3 b) {
        for (size_t i = r.begin(); i != r.end(); ++i) b.extend(photons[i].position);
        return b;
      },
      [](Bounds3 a, const Bounds3& b) {  // min and max are exact: the reduction order does not matter
        if (!b.empty()) a.extend(b.lo), a.extend(b.hi);
        return a;
      });
}

// Cubic cells for about `targetCells` cells over the box. Axes thinner than a cell get one cell,
// and the side is recomputed over the remaining axes (a flat cloud is sized as a 2-D grid).
float cubicCellSide(Vec3 extent, double targetCells) {
  bool thick[3] = {extent.x > 0, extent.y > 0, extent.z > 0};
  float side = 0;
  for (int iteration = 0; iteration < 3; ++iteration) {
    double volume = 1;
    int dims = 0;
    for (int a = 0; a < 3; ++a)
      if (thick[a]) volume *= extent[a], ++dims;
    if (dims == 0) return 1;
    side = float(std::pow(volume / targetCells, 1.0 / dims));
    bool changed = false;
    for (int a = 0; a < 3; ++a)
      if (thick[a] && extent[a] < side) thick[a] = false, changed = true;
    if (!changed) break;
  }
  return side;
}

}  // namespace

UniformGrid makeUniformGrid(std::span<const Photon> photons, const GridOptions& options, uint64_t maxCells) {
  UniformGrid grid;
  const Bounds3 bounds = photons.empty() ? Bounds3{Vec3(0.0f), Vec3(0.0f)} : photonBounds(photons);
  const Vec3 extent = bounds.extent();
  grid.lo = bounds.lo;
  grid.hi = bounds.hi;

  // Cells per axis and their sides.
  const auto& res = options.resolution;
  double cells[3];
  Vec3 side;
  auto cellsFor = [&](Vec3 s) {
    for (int a = 0; a < 3; ++a) cells[a] = std::max(1.0, std::ceil(double(extent[a]) / s[a]));
  };
  if (res[0] > 0 && res[1] > 0 && res[2] > 0) {
    const float fallback = std::max({extent.x, extent.y, extent.z, 1e-30f});
    for (int a = 0; a < 3; ++a) {
      cells[a] = res[a];
      side[a] = extent[a] > 0 ? extent[a] / float(res[a]) : fallback;
    }
  } else {
    const float s = options.cellSize > 0
                        ? options.cellSize
                        : cubicCellSide(extent, std::max(1.0, double(photons.size()) / options.photonsPerCell));
    side = Vec3(s > 0 ? s : 1.0f);
    cellsFor(side);
  }
  // Coarsen until the grid fits: a bound on memory for dense grids, 21 bits per axis for all.
  for (;;) {
    double worst = 1;
    for (int a = 0; a < 3; ++a) worst = std::max(worst, cells[a] / UniformGrid::kMaxResolution);
    if (maxCells > 0) worst = std::max(worst, std::cbrt(cells[0] * cells[1] * cells[2] / double(maxCells)));
    if (worst <= 1) break;
    side = side * float(worst * 1.0001);
    cellsFor(side);
  }
  for (int a = 0; a < 3; ++a) {
    grid.res[a] = int32_t(cells[a]);
    grid.cellSize[a] = side[a];
    grid.invCellSize[a] = 1.0f / side[a];
  }
  // Rounding in cellOf may put a photon a few ulps outside its cell's box; searches allow for it.
  const float magnitude = std::max({std::abs(bounds.lo.x), std::abs(bounds.lo.y), std::abs(bounds.lo.z),
                                    std::abs(bounds.hi.x), std::abs(bounds.hi.y), std::abs(bounds.hi.z),
                                    extent.x, extent.y, extent.z});
  grid.slack = 1e-5f * magnitude;
  return grid;
}

CellCountTable buildCellCountTable(const UniformGrid& grid, const std::function<uint32_t(uint32_t)>& cellCount) {
  CellCountTable t;
  t.res = grid.res;
  const size_t nx = size_t(grid.res[0]) + 1, ny = size_t(grid.res[1]) + 1, nz = size_t(grid.res[2]) + 1;
  t.prefix.assign(nx * ny * nz, 0);
  uint32_t* p = t.prefix.data();
  // Along x, one work item per row of cells; then y per (x, z) column; then z per (x, y) column.
  tbb::parallel_for(tbb::blocked_range<size_t>(1, ny * nz, 64), [&](const auto& r) {
    stopPoint();
    for (size_t row = r.begin(); row != r.end(); ++row) {
      const size_t y = row % ny, z = row / ny;
      if (y == 0 || z == 0) continue;
      uint32_t* out = p + row * nx;
      const uint32_t first = grid.cellIndex({0, int32_t(y - 1), int32_t(z - 1)});
      for (size_t x = 1; x < nx; ++x) out[x] = out[x - 1] + cellCount(first + uint32_t(x - 1));
    }
  });
  tbb::parallel_for(tbb::blocked_range<size_t>(0, nz, 1), [&](const auto& r) {
    stopPoint();
    for (size_t z = r.begin(); z != r.end(); ++z)
      for (size_t y = 1; y < ny; ++y)
        for (size_t x = 0; x < nx; ++x) p[(z * ny + y) * nx + x] += p[(z * ny + y - 1) * nx + x];
  });
  tbb::parallel_for(tbb::blocked_range<size_t>(0, ny, 1), [&](const auto& r) {
    stopPoint();
    for (size_t y = r.begin(); y != r.end(); ++y)
      for (size_t z = 1; z < nz; ++z)
        for (size_t x = 0; x < nx; ++x) p[(z * ny + y) * nx + x] += p[((z - 1) * ny + y) * nx + x];
  });
  return t;
}

std::vector<Photon> gatherPhotons(const std::vector<Photon>& photons, const std::vector<uint32_t>& ids) {
  std::vector<Photon> gathered(ids.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, ids.size(), kItemsPerTask), [&](const auto& r) {
    stopPoint();
    for (size_t i = r.begin(); i != r.end(); ++i) gathered[i] = photons[ids[i]];
  });
  return gathered;
}

}  // namespace lucent
