// The tiles of one level of parallel best-candidate sampling (point_sampling.cpp has the whole
// scheme): candidate and point keys, the tile grid, neighbour lookup, candidate generation, and the
// per-tile kernel that places a tile's new points.
#pragma once
#include <algorithm>
#include <cstdint>
#include <experimental/simd>
#include <span>
#include <vector>

#include "lucent/core/distribution.h"
#include "lucent/core/rng.h"
#include "lucent/core/sampling.h"
#include "lucent/methods/points/point_hierarchy.h"

namespace lucent::points {

namespace stdx = std::experimental;

constexpr uint32_t kTileBits = 21;
constexpr uint32_t kMaxTileCoord = (1u << kTileBits) - 1;

struct CandidateKey {
  uint64_t tile;
  uint64_t triangleIndex;  // triangle << 32 | candidate index within the level
  uint32_t triangle() const { return uint32_t(triangleIndex >> 32); }
  uint32_t index() const { return uint32_t(triangleIndex); }
  bool operator<(const CandidateKey& o) const {
    return tile < o.tile || (tile == o.tile && triangleIndex < o.triangleIndex);
  }
};

struct PointKey {
  uint64_t tile;
  uint32_t point;
  bool operator<(const PointKey& o) const { return tile != o.tile ? tile < o.tile : point < o.point; }
};

// A tile of the level: its placed points in `placed[placedBegin, placedEnd)`, its candidates in
// `candidates[candBegin, candEnd)` and so its new points from index ceil(candBegin / c).
struct Tile {
  uint64_t key = 0;
  uint32_t placedBegin = 0, placedEnd = 0;
  uint32_t candBegin = 0, candEnd = 0;
};

struct TileGrid {
  Vec3 origin;
  float inverseSize = 1;
  uint64_t keyOf(Vec3 p) const {
    uint64_t key = 0;
    for (int a = 0; a < 3; ++a) {
      const float u = (p[a] - origin[a]) * inverseSize;
      const auto c = uint64_t(std::clamp(u, 0.0f, float(kMaxTileCoord)));
      key |= c << (kTileBits * a);
    }
    return key;
  }
};
inline uint32_t tileCoord(uint64_t key, int axis) { return uint32_t(key >> (kTileBits * axis)) & kMaxTileCoord; }
inline uint32_t tileColour(uint64_t key) {
  return (tileCoord(key, 0) & 1u) | (tileCoord(key, 1) & 1u) << 1 | (tileCoord(key, 2) & 1u) << 2;
}

// The tiles around tiles visited in increasing key order. Keys order tiles by z, y, x, so the up to
// three neighbours in each of the 9 rows (dy, dz) are consecutive in the sorted tile array; a cursor
// per row only moves forward as x grows, so the 27 neighbours cost O(1) amortized and are read in
// memory order (a hash lookup per neighbour, a cache miss each, was the sampler's largest cost).
class NeighbourRows {
 public:
  explicit NeighbourRows(std::span<const Tile> tiles) : tiles_(tiles) {}

  // f(tile) for every tile within one tile of `key` (the tile itself included).
  template <class F>
  void forEach(uint64_t key, F&& f) {
    const uint32_t x = tileCoord(key, 0), y = tileCoord(key, 1), z = tileCoord(key, 2);
    const uint64_t xLo = x > 0 ? x - 1 : 0, xHi = std::min(x + 1, kMaxTileCoord);
    int k = 0;
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy, ++k) {
        const int64_t yy = int64_t(y) + dy, zz = int64_t(z) + dz;
        if (yy < 0 || zz < 0 || yy > kMaxTileCoord || zz > kMaxTileCoord) continue;
        const uint64_t row = uint64_t(yy) << kTileBits | uint64_t(zz) << (2 * kTileBits);
        const uint64_t lo = row | xLo, hi = row | xHi;
        size_t& pos = pos_[k];
        if (row_[k] != row || lo < lo_[k]) {
          pos = size_t(std::lower_bound(tiles_.begin(), tiles_.end(), lo,
                                        [](const Tile& t, uint64_t v) { return t.key < v; }) - tiles_.begin());
        } else {
          while (pos < tiles_.size() && tiles_[pos].key < lo) ++pos;
        }
        row_[k] = row, lo_[k] = lo;
        for (size_t p = pos; p < tiles_.size() && tiles_[p].key <= hi; ++p) f(tiles_[p]);
      }
  }

 private:
  std::span<const Tile> tiles_;
  uint64_t row_[9] = {~0ull, ~0ull, ~0ull, ~0ull, ~0ull, ~0ull, ~0ull, ~0ull, ~0ull};
  uint64_t lo_[9] = {};
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
  std::span<const CandidateKey> sortedCandidates;
  std::span<const Vec3> placedByTile;  // points of earlier levels, in Tile::placedBegin order
  uint32_t placed = 0;                 // points of earlier levels; new point k goes to placed + k
  // Written at this tile's new points only; read at the new points of neighbours of earlier colours.
  std::span<PointSample> points;
  std::span<Vec3> positions;
};

// The work item of colour phase `colour`: places the tile's new points one after the other, each the
// candidate farthest from the points in the 27-tile neighbourhood. Returns how many points had fewer
// than c/2 candidates.
uint32_t placeTilePoints(const BestCandidateLevel& level, const Tile& tile, uint32_t colour, NeighbourRows& rows,
                         NeighbourList& neighbours);

}  // namespace lucent::points
