// Best-candidate sampling of points on the scene's triangles (paper 2.1; Mitchell 1991), in parallel
// and deterministic.
//
// Sequential best-candidate places one point at a time, each the candidate farthest from all points
// so far. Here points are added in levels that double their number (1, 1, 2, 4, ... n/2), as the
// sequential process passes through those counts. Within a level:
//  1. c candidates per new point, uniform by area over the whole scene, keyed by (seed, level, index).
//  2. Space is cut into cubic tiles of about tileScale point spacings of the level, so that every
//     point within a tile's edge T of a candidate lies in the candidate's tile or its 26 neighbours.
//     Candidates are sorted by (tile, triangle, index) (a stable radix sort by tile and triangle);
//     a run of one triangle in one tile is a piece.
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

#include <algorithm>
#include <bit>
#include <cmath>
#include <functional>
#include <stdexcept>
#include <string>

#include "best_candidate_tiles.h"
#include "lucent/core/parallel.h"
#include "lucent/core/sobol.h"
#include "lucent/core/stop.h"
#include "radix_sort.h"

namespace lucent {

namespace {
constexpr uint32_t kMaxPoints = 1u << 26;
constexpr uint32_t kMaxCandidates = 64;
}  // namespace

namespace {

// Sobol points 0 .. count - 1 by area: each triangle gets its share of the sequence's first
// coordinate, which a (0, m, 1)-net stratifies, so its count is its area's share to within one
// point per interval of the area distribution.
std::vector<PointSample> sampleLowDiscrepancy(const Distribution1D& areas, uint32_t count, uint64_t seed) {
  std::vector<PointSample> points(count);
  uint32_t scramble[3];
  for (int d = 0; d < 3; ++d) scramble[d] = uint32_t(hashKey(seed, 0x50b01u, uint64_t(d)));
  tbb::parallel_for(tbb::blocked_range<uint32_t>(0, count, kItemsPerTask), [&](const auto& r) {
    stopPoint();
    for (uint32_t i = r.begin(); i != r.end(); ++i) {
      const uint32_t triangle = areas.pick(sobolSample(i, 0, scramble[0]));
      const Vec2 b = sampleUniformTriangle({sobolSample(i, 1, scramble[1]), sobolSample(i, 2, scramble[2])});
      points[i] = {triangle, b.x, b.y};
    }
  });
  return points;
}

// The sampling's request checked; the scene's total area.
double checkedTotalArea(const Scene& scene, uint32_t count, const PointSamplingOptions& options) {
  if (count == 0 || count > kMaxPoints)
    throw std::invalid_argument("point sampling: the point count must be 1 .. 2^26, not " + std::to_string(count));
  if (options.candidates == 0 || options.candidates > kMaxCandidates)
    throw std::invalid_argument("point sampling: candidates must be 1 .. 64, not " + std::to_string(options.candidates));
  if (!(options.tileScale >= 1.0f && options.tileScale <= 64.0f))
    throw std::invalid_argument("point sampling: tileScale must be in [1, 64]");
  if (scene.triangleCount() == 0 || scene.faceAreas.size() != scene.triangleCount())
    throw std::invalid_argument("point sampling: the scene has no (finalized) triangles");
  double totalArea = 0;
  for (float a : scene.faceAreas) totalArea += a;
  if (!(totalArea > 0) || !std::isfinite(totalArea))
    throw std::invalid_argument("point sampling: the scene's triangles have no area");
  return totalArea;
}

// The tiles of a level: every key of either sorted list (the candidates' keys hold their triangle
// below the tile), merged, with the run of each list it holds.
void mergeTiles(const std::vector<uint64_t>& placedKeys, const std::vector<uint64_t>& candKeys, uint32_t triangleBits,
                std::vector<points::Tile>& tiles) {
  using points::Tile;
  const size_t placed = placedKeys.size(), candCount = candKeys.size();
  tiles.clear();
  for (uint32_t i = 0, j = 0; i < placed || j < candCount;) {
    const uint64_t key = std::min(i < placed ? placedKeys[i] : ~uint64_t(0),
                                  j < candCount ? candKeys[j] >> triangleBits : ~uint64_t(0));
    Tile t;
    t.key = key;
    t.placedBegin = i;
    while (i < placed && placedKeys[i] == key) ++i;
    t.placedEnd = i;
    t.candBegin = j;
    while (j < candCount && candKeys[j] >> triangleBits == key) ++j;
    t.candEnd = j;
    tiles.push_back(t);
  }
}

}  // namespace

namespace points {
namespace {

// Best-candidate sampling, level by level: each level doubles the points, each new point the best
// of c candidates, placed tile by tile in eight colours so that neighbouring tiles never run at once.
// Counts the candidates drawn and the points that had fewer than c / 2 to choose from.
std::vector<PointSample> sampleBestCandidate(const Scene& scene, uint32_t count, const PointSamplingOptions& options,
                                             const Distribution1D& areas, double totalArea,
                                             uint64_t& candidatesTotal, uint64_t& fewTotal) {
  const uint32_t c = options.candidates;
  Bounds3 bounds;
  for (const Vec3& p : scene.positions) bounds.extend(p);

  std::vector<PointSample> points(count);
  std::vector<Vec3> positions(count);
  tbb::enumerable_thread_specific<NeighbourList> scratch;
  tbb::enumerable_thread_specific<uint64_t> fewCandidates(0);  // points with fewer than c/2
  // Reused from level to level: fresh pages cost more than the sorts that fill them.
  std::vector<uint64_t> placedKeys, candKeys, keyScratch;
  std::vector<uint32_t> placedIndices, candIndices, indexScratch;
  std::vector<Vec3> placedByTile;  // positions in sorted order: neighbour lists read them in runs
  std::vector<Tile> tiles;
  // The last level is the largest: reserve for it once rather than growing (and faulting in fresh
  // pages) level after level.
  const size_t mostCandidates = size_t(c) * (count / 2 + 1), mostKeys = std::max<size_t>(mostCandidates, count);
  placedKeys.reserve(count), placedIndices.reserve(count), placedByTile.reserve(count);
  candKeys.reserve(mostCandidates), candIndices.reserve(mostCandidates);
  keyScratch.reserve(mostKeys), indexScratch.reserve(mostKeys);
  const auto triangleBits = uint32_t(std::bit_width(scene.triangleCount() - 1));

  // Level 0 places the first point, level L >= 1 adds 2^(L-1) (the last level of a count that is not
  // a power of two fewer).
  uint32_t placed = 0;
  for (uint32_t level = 0; placed < count; ++level) {
    const uint32_t adding = level == 0 ? 1 : std::min(placed, count - placed);
    const uint32_t total = placed + adding;
    const uint32_t candCount = adding * c;
    candidatesTotal += candCount;

    // Tile edge: tileScale mean spacings of the points after this level, sqrt(area / total);
    // coarser where a (tile, triangle) key would not fit 64 bits.
    float tileSize = options.tileScale * float(std::sqrt(totalArea / total));
    if (!(tileSize > 0)) tileSize = 1;
    TileGrid grid(bounds, tileSize);
    while (grid.keyBits() + triangleBits > 64) grid = TileGrid(bounds, tileSize *= 2);
    const float cap2 = tileSize * tileSize;

    // Placed points and candidates, sorted by tile (and triangle) by a stable radix sort, so that
    // equal keys stay in index order.
    placedKeys.resize(placed);
    placedIndices.resize(placed);
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, placed, kItemsPerTask), [&](const auto& r) {
      stopPoint();
      for (uint32_t i = r.begin(); i != r.end(); ++i) placedKeys[i] = grid.keyOf(positions[i]), placedIndices[i] = i;
    });
    radixSortByKey(placedKeys, placedIndices, grid.keyBits(), keyScratch, indexScratch);
    placedByTile.resize(placed);
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, placed, kItemsPerTask), [&](const auto& r) {
      stopPoint();
      for (uint32_t i = r.begin(); i != r.end(); ++i) placedByTile[i] = positions[placedIndices[i]];
    });
    candKeys.resize(candCount);
    candIndices.resize(candCount);
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, candCount, kItemsPerTask), [&](const auto& r) {
      stopPoint();
      for (uint32_t i = r.begin(); i != r.end(); ++i) {
        const PointSample s = candidateAt(areas, options.seed, level, i);
        candKeys[i] = grid.keyOf(pointPosition(scene, s)) << triangleBits | s.triangle;
        candIndices[i] = i;
      }
    });
    radixSortByKey(candKeys, candIndices, grid.keyBits() + triangleBits, keyScratch, indexScratch);

    mergeTiles(placedKeys, candKeys, triangleBits, tiles);
    std::vector<uint32_t> byColour[8];
    for (uint32_t t = 0; t < tiles.size(); ++t)
      if (tiles[t].candEnd > tiles[t].candBegin) byColour[grid.colour(tiles[t].key)].push_back(t);

    BestCandidateLevel view;
    view.scene = &scene;
    view.seed = options.seed;
    view.level = level;
    view.candidates = c;
    view.grid = grid;
    view.cap2 = cap2;
    view.candidateKeys = candKeys;
    view.candidateIndices = candIndices;
    view.triangleBits = triangleBits;
    view.placedByTile = placedByTile;
    view.placed = placed;
    view.points = points;
    view.positions = positions;
    for (uint32_t colour = 0; colour < 8; ++colour) {
      const std::vector<uint32_t>& list = byColour[colour];
      tbb::parallel_for(tbb::blocked_range<size_t>(0, list.size(), 16), [&](const auto& r) {
        stopPoint();
        NeighbourList& nb = scratch.local();
        NeighbourRows rows(tiles, view.grid);
        uint64_t few = 0;
        for (size_t li = r.begin(); li != r.end(); ++li) few += placeTilePoints(view, tiles[list[li]], colour, rows, nb);
        fewCandidates.local() += few;
      });
    }
    placed = total;
  }
  fewTotal = fewCandidates.combine(std::plus<uint64_t>());
  return points;
}

}  // namespace
}  // namespace points

std::vector<PointSample> samplePoints(const Scene& scene, uint32_t count, const PointSamplingOptions& options,
                                      RenderStats* stats) {
  const double totalArea = checkedTotalArea(scene, count, options);
  const Distribution1D areas(scene.faceAreas);

  beginStage("point_sampling");
  Stopwatch clock;
  const bool bestCandidate = options.method != PointSampling::LowDiscrepancy;
  uint64_t candidates = 0, few = 0;
  std::vector<PointSample> points =
      bestCandidate ? points::sampleBestCandidate(scene, count, options, areas, totalArea, candidates, few)
                    : sampleLowDiscrepancy(areas, count, options.seed);
  if (stats) {
    stats->addStage("point_sampling", clock.seconds());
    stats->addCounter("points", count);
    if (bestCandidate) {
      stats->addCounter("point_candidates", candidates);
      stats->addCounter("points_with_few_candidates", few);
    }
  }
  return points;
}

}  // namespace lucent
