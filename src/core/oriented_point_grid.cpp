#include "lucent/core/oriented_point_grid.h"

#include <algorithm>

namespace lucent {

OrientedPointGrid buildOrientedPointGrid(std::span<const OrientedPoint> points, float cellSize) {
  OrientedPointGrid g;
  Bounds3 b;
  for (const OrientedPoint& p : points) b.extend(p.position);
  if (b.empty()) b.extend({0, 0, 0});
  const Vec3 e = b.extent();
  constexpr double kMaxCells = double(1 << 24);
  double cell = std::max<double>(cellSize, 1e-30);
  auto cells = [&](double c) {
    return (std::floor(e.x / c) + 1) * (std::floor(e.y / c) + 1) * (std::floor(e.z / c) + 1);
  };
  while (cells(cell) > kMaxCells) cell *= 1.25;
  g.origin = b.lo;
  g.cellSize = float(cell);
  g.nx = int(std::floor(e.x / cell)) + 1;
  g.ny = int(std::floor(e.y / cell)) + 1;
  g.nz = int(std::floor(e.z / cell)) + 1;
  const size_t n = size_t(g.nx) * size_t(g.ny) * size_t(g.nz);
  auto cellOf = [&](Vec3 p) {
    return g.cellIndex(g.cellCoord(p.x, g.origin.x, g.nx), g.cellCoord(p.y, g.origin.y, g.ny),
                       g.cellCoord(p.z, g.origin.z, g.nz));
  };
  g.cellStart.assign(n + 1, 0);
  for (const OrientedPoint& p : points) ++g.cellStart[cellOf(p.position) + 1];
  for (size_t c = 0; c < n; ++c) g.cellStart[c + 1] += g.cellStart[c];
  g.points.resize(points.size());
  std::vector<uint32_t> next(g.cellStart.begin(), g.cellStart.end() - 1);
  for (const OrientedPoint& p : points) g.points[next[cellOf(p.position)]++] = p;
  return g;
}

}  // namespace lucent
