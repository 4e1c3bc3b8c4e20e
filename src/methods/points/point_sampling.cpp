// Best-candidate sampling of points on the scene's triangles (paper 2.1; Mitchell 1991), in parallel
// and deterministic.
//
// Sequential best-candidate places one point at a time, each the candidate farthest from all points
// so far. Here points are added in levels that double their number (1, 1, 2, 4, ... n/2), as the
// sequential process passes through those counts. Within a level:
//  1. c candidates per new point, uniform by area over the whole scene, keyed by (seed, level, index).
//  2. Space is cut into cubic tiles of about tileScale point spacings of the level, so that every
//     point within a tile's edge T of a candidate lies in the candidate's tile or its 26 neighbours.
//     Candidates are sorted by (tile, triangle, index); a run of one triangle in one tile is a piece.
//  3. The new points are dealt out in that order, one per c candidates: a piece gets as many points
//     as multiples of c fall among its sorted ranks, and its points share its candidates evenly. A
//     point's candidates are therefore all on its own triangle, so each triangle gets points in
//     proportion to its candidates, i.e. to its area, even where surfaces nearly coincide (the
//     Cornell box's light 0.8 below the ceiling): points compete for room, never for area. (The
//     counts are also less noisy than multinomial ones: about 1/c of the variance.) Points of
//     pieces with fewer than c candidates get more, uniform on the piece by rejection.
//  4. Tiles are processed in 8 colour phases by the parities of their coordinates. A tile reads the
//     points of its 27-tile neighbourhood and writes only its own new points; tiles of one colour are
//     two tiles apart, so they never read each other's writes and run in parallel, and which
//     neighbours' new points a tile sees (those of earlier colours) does not depend on the schedule.
//     Within a tile, its points are placed one after the other: each takes the candidate whose
//     nearest placed point is farthest, with distances capped at T (exact below the cap), ties to
//     the lowest candidate index.
// Each level costs O(its points) plus a sort, so the whole is O(n log n) in the sorts and O(n) in
// the distance evaluations.
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <experimental/simd>
#include <functional>
#include <stdexcept>
#include <string>

#include "lucent/core/distribution.h"
#include "lucent/core/rng.h"
#include "lucent/core/sampling.h"
#include "lucent/methods/points/point_hierarchy.h"

namespace lucent {

namespace {

namespace stdx = std::experimental;

constexpr uint32_t kMaxPoints = 1u << 26;
constexpr uint32_t kMaxCandidates = 64;
constexpr uint32_t kTileBits = 21;
constexpr uint32_t kMaxTileCoord = (1u << kTileBits) - 1;
constexpr size_t kGrain = 4096;

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
uint32_t tileCoord(uint64_t key, int axis) { return uint32_t(key >> (kTileBits * axis)) & kMaxTileCoord; }
uint32_t tileColour(uint64_t key) {
  return (tileCoord(key, 0) & 1u) | (tileCoord(key, 1) & 1u) << 1 | (tileCoord(key, 2) & 1u) << 2;
}

// The tiles around tiles visited in increasing key order. Keys order tiles by z, y, x, so the up to
// three neighbours in each of the 9 rows (dy, dz) are consecutive in the sorted tile array; a cursor
// per row only moves forward as x grows, so the 27 neighbours cost O(1) amortized and are read in
// memory order (a hash lookup per neighbour, a cache miss each, was the sampler's largest cost).
class NeighbourRows {
 public:
  explicit NeighbourRows(const std::vector<Tile>& tiles) : tiles_(tiles) {}

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
  const std::vector<Tile>& tiles_;
  uint64_t row_[9] = {~0ull, ~0ull, ~0ull, ~0ull, ~0ull, ~0ull, ~0ull, ~0ull, ~0ull};
  uint64_t lo_[9] = {};
  size_t pos_[9] = {};
};

// Candidate `index` of `level`: a triangle by area, then a point uniform on it. Given the triangle
// (from the sorted keys), only the barycentrics are drawn again.
PointSample candidateAt(const Distribution1D& areas, uint64_t seed, uint32_t level, uint32_t index) {
  Rng rng(seed, level, index);
  const uint32_t triangle = areas.sampleDiscrete(rng.uniform());
  const Vec2 b = sampleUniformTriangle(rng.uniform2());
  return {triangle, b.x, b.y};
}
PointSample candidateOn(uint32_t triangle, uint64_t seed, uint32_t level, uint32_t index) {
  Rng rng(seed, level, index);
  rng.next();
  const Vec2 b = sampleUniformTriangle(rng.uniform2());
  return {triangle, b.x, b.y};
}

// Extra candidate t on a triangle for the point whose first candidate is `first` (a key no regular
// candidate uses).
constexpr uint32_t kTopUpTries = 4;
PointSample topUpCandidate(uint32_t triangle, uint64_t seed, uint32_t level, uint32_t first, uint32_t t) {
  Rng rng(hashKey(seed, level, 0x70b0b5u), first, t);
  const Vec2 b = sampleUniformTriangle(rng.uniform2());
  return {triangle, b.x, b.y};
}

// Per-thread neighbour list, structure of arrays so the distance loop vectorizes.
struct Neighbours {
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
uint32_t pointsBefore(uint32_t rank, uint32_t c) { return uint32_t((uint64_t(rank) + c - 1) / c); }

}  // namespace

std::vector<PointSample> samplePoints(const Scene& scene, uint32_t count, const PointSamplingOptions& options,
                                      RenderStats* stats) {
  if (count == 0 || count > kMaxPoints)
    throw std::invalid_argument("point sampling: the point count must be 1 .. 2^26, not " + std::to_string(count));
  const uint32_t c = options.candidates;
  if (c == 0 || c > kMaxCandidates)
    throw std::invalid_argument("point sampling: candidates must be 1 .. 64, not " + std::to_string(c));
  if (!(options.tileScale >= 1.0f && options.tileScale <= 64.0f))
    throw std::invalid_argument("point sampling: tileScale must be in [1, 64]");
  if (scene.triangleCount() == 0 || scene.faceAreas.size() != scene.triangleCount())
    throw std::invalid_argument("point sampling: the scene has no (finalized) triangles");
  const Distribution1D areas(scene.faceAreas);
  double totalArea = 0;
  for (float a : scene.faceAreas) totalArea += a;
  if (!(totalArea > 0) || !std::isfinite(totalArea))
    throw std::invalid_argument("point sampling: the scene's triangles have no area");

  Stopwatch clock;
  Bounds3 bounds;
  for (const Vec3& p : scene.positions) bounds.extend(p);
  const float extent = std::max({bounds.extent().x, bounds.extent().y, bounds.extent().z});

  std::vector<PointSample> points(count);
  std::vector<Vec3> positions(count);
  tbb::enumerable_thread_specific<Neighbours> scratch;
  tbb::enumerable_thread_specific<uint64_t> fewCandidates(0);  // points with fewer than c/2
  uint64_t candidatesTotal = 0;
  // Reused from level to level: fresh pages cost more than the sorts that fill them.
  std::vector<PointKey> placedKeys;
  std::vector<Vec3> placedByTile;  // positions in placedKeys order: neighbour lists read them in runs
  std::vector<CandidateKey> cand;
  std::vector<Tile> tiles;

  // Level 0 places the first point, level L >= 1 adds 2^(L-1) (the last level of a count that is not
  // a power of two fewer).
  uint32_t placed = 0;
  for (uint32_t level = 0; placed < count; ++level) {
    const uint32_t adding = level == 0 ? 1 : std::min(placed, count - placed);
    const uint32_t total = placed + adding;
    const uint32_t candCount = adding * c;
    candidatesTotal += candCount;

    // Tile edge: tileScale mean spacings of the points after this level, sqrt(area / total),
    // kept within 21-bit coordinates.
    float tileSize = options.tileScale * float(std::sqrt(totalArea / total));
    tileSize = std::max(tileSize, extent / float(kMaxTileCoord - 1));
    if (!(tileSize > 0)) tileSize = 1;
    const TileGrid grid{bounds.lo, 1.0f / tileSize};
    const float cap2 = tileSize * tileSize;

    // Placed points and candidates, sorted by tile.
    placedKeys.resize(placed);
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, placed, kGrain), [&](const auto& r) {
      for (uint32_t i = r.begin(); i != r.end(); ++i) placedKeys[i] = {grid.keyOf(positions[i]), i};
    });
    tbb::parallel_sort(placedKeys.begin(), placedKeys.end());
    placedByTile.resize(placed);
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, placed, kGrain), [&](const auto& r) {
      for (uint32_t i = r.begin(); i != r.end(); ++i) placedByTile[i] = positions[placedKeys[i].point];
    });
    cand.resize(candCount);
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, candCount, kGrain), [&](const auto& r) {
      for (uint32_t i = r.begin(); i != r.end(); ++i) {
        const PointSample s = candidateAt(areas, options.seed, level, i);
        cand[i] = {grid.keyOf(pointPosition(scene, s)), uint64_t(s.triangle) << 32 | i};
      }
    });
    tbb::parallel_sort(cand.begin(), cand.end());

    // The tiles: every key of either list, merged.
    tiles.clear();
    for (uint32_t i = 0, j = 0; i < placed || j < candCount;) {
      const uint64_t key = std::min(i < placed ? placedKeys[i].tile : ~uint64_t(0),
                                    j < candCount ? cand[j].tile : ~uint64_t(0));
      Tile t;
      t.key = key;
      t.placedBegin = i;
      while (i < placed && placedKeys[i].tile == key) ++i;
      t.placedEnd = i;
      t.candBegin = j;
      while (j < candCount && cand[j].tile == key) ++j;
      t.candEnd = j;
      tiles.push_back(t);
    }
    std::vector<uint32_t> byColour[8];
    for (uint32_t t = 0; t < tiles.size(); ++t)
      if (tiles[t].candEnd > tiles[t].candBegin) byColour[tileColour(tiles[t].key)].push_back(t);

    for (uint32_t colour = 0; colour < 8; ++colour) {
      const std::vector<uint32_t>& list = byColour[colour];
      tbb::parallel_for(tbb::blocked_range<size_t>(0, list.size(), 16), [&](const auto& r) {
        Neighbours& nb = scratch.local();
        uint64_t& few = fewCandidates.local();
        NeighbourRows rows(tiles);
        for (size_t li = r.begin(); li != r.end(); ++li) {
          const Tile& tile = tiles[list[li]];
          // The neighbourhood: placed points of the 27 tiles, and the new points of neighbours
          // done in earlier phases.
          nb.clear();
          rows.forEach(tile.key, [&](const Tile& n) {
            for (uint32_t k = n.placedBegin; k < n.placedEnd; ++k) nb.add(placedByTile[k]);
            if (tileColour(n.key) < colour)
              for (uint32_t k = pointsBefore(n.candBegin, c); k < pointsBefore(n.candEnd, c); ++k)
                nb.add(positions[placed + k]);
          });
          // Pieces (one triangle's run of candidates) in order; each point takes its share.
          for (uint32_t a = tile.candBegin; a < tile.candEnd;) {
            uint32_t b = a + 1;
            while (b < tile.candEnd && cand[b].triangle() == cand[a].triangle()) ++b;
            const uint32_t first = pointsBefore(a, c), pieceCount = pointsBefore(b, c) - first;
            const uint32_t m = b - a;
            for (uint32_t j = 0; j < pieceCount; ++j) {
              const uint32_t lo = a + uint32_t(uint64_t(j) * m / pieceCount);
              const uint32_t hi = a + uint32_t(uint64_t(j + 1) * m / pieceCount);
              float bestD2 = -1;
              PointSample best;
              Vec3 bestP;
              auto consider = [&](const PointSample& s, Vec3 p) {
                const float d2 = nb.nearest2(p, cap2);
                if (d2 > bestD2) bestD2 = d2, best = s, bestP = p;
              };
              for (uint32_t k = lo; k < hi; ++k) {
                const PointSample s = candidateOn(cand[k].triangle(), options.seed, level, cand[k].index());
                consider(s, pointPosition(scene, s));
              }
              // A piece too small for its share of c (a small triangle, or a corner of one in the
              // tile): more candidates uniform on the piece, by rejection from the triangle, up to
              // c in all within 4c tries. Counts stay as dealt, so area-proportionality holds.
              uint32_t have = hi - lo;
              for (uint32_t t = 0; have < c && t < kTopUpTries * c; ++t) {
                const PointSample s = topUpCandidate(cand[a].triangle(), options.seed, level, cand[lo].index(), t);
                const Vec3 p = pointPosition(scene, s);
                if (grid.keyOf(p) != tile.key) continue;
                consider(s, p);
                ++have;
              }
              few += 2 * have < c;
              points[placed + first + j] = best;
              positions[placed + first + j] = bestP;
              nb.add(bestP);
            }
            a = b;
          }
        }
      });
    }
    placed = total;
  }

  if (stats) {
    stats->addStage("point_sampling", clock.seconds());
    stats->addCounter("points", count);
    stats->addCounter("point_candidates", candidatesTotal);
    stats->addCounter("points_with_few_candidates", fewCandidates.combine(std::plus<uint64_t>()));
  }
  return points;
}

}  // namespace lucent
