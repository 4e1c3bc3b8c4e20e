// The tiles of one level of parallel best-candidate sampling (point_sampling.cpp has the whole
// scheme): candidate and point keys, the tile grid, neighbour lookup, candidate generation, and the
// per-tile kernel that places a tile's new points.
#pragma once
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <experimental/simd>
#include <span>
#include <vector>

#include "lucent/core/distribution.h"
#include "lucent/core/rng.h"
#include "lucent/core/sampling.h"
#include "lucent/techniques/points/point_hierarchy.h"

namespace lucent::points {

namespace stdx = std::experimental;

// A tile of the level: its placed points at [placedBegin, placedEnd) of the tile-sorted placed
// points, its candidates at [candBegin, candEnd) of the sorted candidates, and so its new points
// from index ceil(candBegin / c).
struct Tile {
  uint64_t key = 0;
  uint32_t placedBegin = 0, placedEnd = 0;
  uint32_t candBegin = 0, candEnd = 0;
};

// Cubic tiles of one level, keyed by their coordinates packed z, y, x from the most significant
// bits in as few bits as the scene's extent needs: keys sort tiles row by row, and a (tile,
// triangle) key fits the 64 bits of the radix sort.
struct TileGrid {
  Vec3 origin;
  float inverseSize = 1;
  uint32_t bits[3] = {0, 0, 0};
  uint32_t maxCoord[3] = {0, 0, 0};

  TileGrid() = default;
  TileGrid(const Bounds3& bounds, float size) : origin(bounds.lo), inverseSize(1.0f / size) {
    for (int a = 0; a < 3; ++a) {
      const float cells = std::floor(std::max(0.0f, bounds.extent()[a]) * inverseSize);
      maxCoord[a] = uint32_t(std::min(cells, float(1u << 21)));
      bits[a] = uint32_t(std::bit_width(maxCoord[a]));
    }
  }
  uint32_t keyBits() const { return bits[0] + bits[1] + bits[2]; }
  uint64_t compose(uint32_t x, uint32_t y, uint32_t z) const {
    return uint64_t(z) << (bits[0] + bits[1]) | uint64_t(y) << bits[0] | x;
  }
  uint64_t keyOf(Vec3 p) const {
    uint32_t c[3];
    for (int a = 0; a < 3; ++a) c[a] = uint32_t(std::clamp((p[a] - origin[a]) * inverseSize, 0.0f, float(maxCoord[a])));
    return compose(c[0], c[1], c[2]);
  }
  uint32_t coord(uint64_t key, int axis) const {
    const uint32_t shift = axis == 0 ? 0 : (axis == 1 ? bits[0] : bits[0] + bits[1]);
    return uint32_t(key >> shift) & ((1u << bits[axis]) - 1);
  }
  // Parities of the coordinates: tiles of one colour are two tiles apart.
  uint32_t colour(uint64_t key) const {
    return (coord(key, 0) & 1u) | (coord(key, 1) & 1u) << 1 | (coord(key, 2) & 1u) << 2;
  }
};

// The tiles around tiles visited in increasing key order. The up to three neighbours in each of the
// 9 rows (dy, dz) are consecutive in the sorted tile array; a cursor per row only moves forward as x
// grows, so the 27 neighbours cost O(1) amortized and are read in memory order (a hash lookup per
// neighbour, a cache miss each, was the sampler's largest cost).
class NeighbourRows {
 public:
  NeighbourRows(std::span<const Tile> tiles, const TileGrid& grid) : tiles_(tiles), grid_(grid) {}

  // f(tile) for every tile within one tile of `key` (the tile itself included).
  template <class F>
  void forEach(uint64_t key, F&& f) {
    const uint32_t x = grid_.coord(key, 0), y = grid_.coord(key, 1), z = grid_.coord(key, 2);
    const uint32_t xLo = x > 0 ? x - 1 : 0, xHi = std::min(x + 1, grid_.maxCoord[0]);
    int k = 0;
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy, ++k) {
        const int64_t yy = int64_t(y) + dy, zz = int64_t(z) + dz;
        if (yy < 0 || zz < 0 || yy > grid_.maxCoord[1] || zz > grid_.maxCoord[2]) continue;
        const uint64_t lo = grid_.compose(xLo, uint32_t(yy), uint32_t(zz));
        const uint64_t hi = grid_.compose(xHi, uint32_t(yy), uint32_t(zz));
        size_t& pos = pos_[k];
        if ((lo >> grid_.bits[0]) != (lo_[k] >> grid_.bits[0]) || lo < lo_[k]) {
          // A new row (or a step back): search; otherwise walk forward along the row.
          pos = size_t(std::lower_bound(tiles_.begin(), tiles_.end(), lo,
                                        [](const Tile& t, uint64_t v) { return t.key < v; }) - tiles_.begin());
        } else {
          while (pos < tiles_.size() && tiles_[pos].key < lo) ++pos;
        }
        lo_[k] = lo;
        for (size_t p = pos; p < tiles_.size() && tiles_[p].key <= hi; ++p) f(tiles_[p]);
      }
  }

 private:
  std::span<const Tile> tiles_;
  const TileGrid& grid_;
  uint64_t lo_[9] = {~0ull, ~0ull, ~0ull, ~0ull, ~0ull, ~0ull, ~0ull, ~0ull, ~0ull};
  size_t pos_[9] = {};
};

// Candidate `index` of `level`: a triangle by area, then a point uniform on it. Given the triangle
// (from the sorted keys), only the barycentrics are drawn again.
inline PointSample candidateAt(const Distribution1D& areas, uint64_t seed, uint32_t level, uint32_t index) {
  Rng rng(seed, level, index);
  const uint32_t triangle = areas.sampleDiscrete(rng.uniform());
  const Vec2 b = sampleUniformTriangle(rng.uniform2());
  return {triangle, b.x, b.y};
}
inline PointSample candidateOn(uint32_t triangle, uint64_t seed, uint32_t level, uint32_t index) {
  Rng rng(seed, level, index);
  rng.next();
  const Vec2 b = sampleUniformTriangle(rng.uniform2());
  return {triangle, b.x, b.y};
}

// Extra candidate t on a triangle for the point whose first candidate is `first` (a key no regular
// candidate uses).
constexpr uint32_t kTopUpTries = 4;
inline PointSample topUpCandidate(uint32_t triangle, uint64_t seed, uint32_t level, uint32_t first, uint32_t t) {
  Rng rng(hashKey(seed, level, 0x70b0b5u), first, t);
  const Vec2 b = sampleUniformTriangle(rng.uniform2());
  return {triangle, b.x, b.y};
}

// Per-thread neighbour list, structure of arrays so the distance loop vectorizes; it grows only
// until it fits the largest neighbourhood.
struct NeighbourList {
  std::vector<float> x, y, z;
  void clear() { x.clear(), y.clear(), z.clear(); }
  void add(Vec3 p) { x.push_back(p.x), y.push_back(p.y), z.push_back(p.z); }
  // Squared distance from p to the nearest neighbour, at most cap2, in SIMD lanes (the compiler does
  // not vectorize the min reduction without reassociation, which -ffast-math would allow).
  float nearest2(Vec3 p, float cap2) const {
    using V = stdx::native_simd<float>;
    constexpr size_t kWidth = V::size();
    const size_t n = x.size(), whole = n - n % kWidth;
    const V px(p.x), py(p.y), pz(p.z);
    V lanes(cap2);
    for (size_t i = 0; i < whole; i += kWidth) {
      const V dx = V(&x[i], stdx::element_aligned) - px;
      const V dy = V(&y[i], stdx::element_aligned) - py;
      const V dz = V(&z[i], stdx::element_aligned) - pz;
      lanes = stdx::min(lanes, dx * dx + dy * dy + dz * dz);
    }
    float best = stdx::hmin(lanes);
    for (size_t i = whole; i < n; ++i) {
      const float dx = x[i] - p.x, dy = y[i] - p.y, dz = z[i] - p.z;
      best = std::min(best, dx * dx + dy * dy + dz * dz);
    }
    return best;
  }
};

// ceil(a / c): the first new point dealt out at or after candidate rank a.
inline uint32_t pointsBefore(uint32_t rank, uint32_t c) { return uint32_t((uint64_t(rank) + c - 1) / c); }

// What one level's tile work items read and write.
struct BestCandidateLevel {
  const Scene* scene = nullptr;
  uint64_t seed = 0;
  uint32_t level = 0;
  uint32_t candidates = 0;  // c
  TileGrid grid;
  float cap2 = 0;  // squared tile edge: distances are capped there
  // Candidates sorted by (tile key << triangleBits | triangle), then index.
  std::span<const uint64_t> candidateKeys;
  std::span<const uint32_t> candidateIndices;
  uint32_t triangleBits = 0;
  std::span<const Vec3> placedByTile;  // points of earlier levels, in Tile::placedBegin order
  uint32_t placed = 0;                 // points of earlier levels; new point k goes to placed + k
  // Written at this tile's new points only; read at the new points of neighbours of earlier colours.
  std::span<PointSample> points;
  std::span<Vec3> positions;

  uint32_t triangleOf(uint32_t rank) const { return uint32_t(candidateKeys[rank] & ((uint64_t(1) << triangleBits) - 1)); }
};

// The work item of colour phase `colour`: places the tile's new points one after the other, each the
// candidate farthest from the points in the 27-tile neighbourhood. Returns how many points had fewer
// than c/2 candidates.
uint32_t placeTilePoints(const BestCandidateLevel& level, const Tile& tile, uint32_t colour, NeighbourRows& rows,
                         NeighbourList& neighbours);

}  // namespace lucent::points
