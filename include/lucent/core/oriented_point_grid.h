// A uniform grid over oriented points (a position, a normal and an index each), for the nearest
// point that passes a test (the particle that faces a hit's side, the precomputed irradiance that
// lights a gather ray's hit) and for the points within a radius. A cell's points lie next to each
// other in memory, so a lookup touches a few cache lines per cell, not one per point.
#pragma once
#include <cmath>
#include <cstdint>
#include <span>
#include <type_traits>
#include <vector>

#include "lucent/core/math.h"

namespace lucent {

struct OrientedPoint {
  Vec3 position;
  Vec3 normal;
  uint32_t id;
};
static_assert(sizeof(OrientedPoint) == 28 && std::is_trivially_copyable_v<OrientedPoint>);

inline constexpr uint32_t kNoPoint = 0xffffffffu;

// The points of cell c are points[cellStart[c] .. cellStart[c + 1]), in index order.
struct OrientedPointGrid {
  Vec3 origin;
  float cellSize = 1;
  int nx = 1, ny = 1, nz = 1;
  std::vector<uint32_t> cellStart;
  std::vector<OrientedPoint> points;

  int cellCoord(float v, float o, int n) const {
    const float c = (v - o) / cellSize;
    return c <= 0 ? 0 : c >= float(n - 1) ? n - 1 : int(c);
  }
  size_t cellIndex(int x, int y, int z) const { return (size_t(z) * size_t(ny) + size_t(y)) * size_t(nx) + size_t(x); }

  // visit(const OrientedPoint&) for every point in the cells that overlap the cube of half-side
  // `radius` about p.
  template <class Visit>
  void forEachNear(Vec3 p, float radius, Visit visit) const {
    const int x0 = cellCoord(p.x - radius, origin.x, nx), x1 = cellCoord(p.x + radius, origin.x, nx);
    const int y0 = cellCoord(p.y - radius, origin.y, ny), y1 = cellCoord(p.y + radius, origin.y, ny);
    const int z0 = cellCoord(p.z - radius, origin.z, nz), z1 = cellCoord(p.z + radius, origin.z, nz);
    for (int z = z0; z <= z1; ++z)
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
          const size_t c = cellIndex(x, y, z);
          for (uint32_t k = cellStart[c]; k < cellStart[c + 1]; ++k) visit(points[k]);
        }
  }

  // The index of the point nearest to p within `radius` that accept(point, squared distance)
  // takes; kNoPoint if there is none. Of equally near ones, the lowest index. The point's own cell
  // is searched first, then the cells out to the best distance found, each skipped when all of it
  // is farther than the best.
  template <class Accept>
  uint32_t nearest(Vec3 p, float radius, Accept accept) const {
    uint32_t best = kNoPoint;
    float bestD2 = radius * radius;
    auto visitCell = [&](int x, int y, int z) {
      const size_t c = cellIndex(x, y, z);
      for (uint32_t k = cellStart[c]; k < cellStart[c + 1]; ++k) {
        const OrientedPoint& q = points[k];
        const Vec3 d = q.position - p;
        const float d2 = dot(d, d);
        if ((d2 < bestD2 || (d2 == bestD2 && q.id < best)) && accept(q, d2)) bestD2 = d2, best = q.id;
      }
    };
    const int cx = cellCoord(p.x, origin.x, nx), cy = cellCoord(p.y, origin.y, ny), cz = cellCoord(p.z, origin.z, nz);
    visitCell(cx, cy, cz);
    const float reach = std::sqrt(bestD2);
    const int x0 = cellCoord(p.x - reach, origin.x, nx), x1 = cellCoord(p.x + reach, origin.x, nx);
    const int y0 = cellCoord(p.y - reach, origin.y, ny), y1 = cellCoord(p.y + reach, origin.y, ny);
    const int z0 = cellCoord(p.z - reach, origin.z, nz), z1 = cellCoord(p.z + reach, origin.z, nz);
    auto gap = [&](int i, float v, float o) {  // distance along an axis from v to cell i
      const float lo = o + float(i) * cellSize, hi = lo + cellSize;
      return v < lo ? lo - v : v > hi ? v - hi : 0.0f;
    };
    for (int z = z0; z <= z1; ++z) {
      const float dz = gap(z, p.z, origin.z);
      for (int y = y0; y <= y1; ++y) {
        const float dy = gap(y, p.y, origin.y);
        for (int x = x0; x <= x1; ++x) {
          if (x == cx && y == cy && z == cz) continue;
          const float dx = gap(x, p.x, origin.x);
          if (dx * dx + dy * dy + dz * dz > bestD2) continue;
          visitCell(x, y, z);
        }
      }
    }
    return best;
  }
};

// A grid of cells about `cellSize` wide (wider where the points' bounds would need more than 2^24
// cells), by a stable counting sort.
OrientedPointGrid buildOrientedPointGrid(std::span<const OrientedPoint> points, float cellSize);

}  // namespace lucent
