// The per-tile work item of parallel best-candidate sampling (paper 2.1; Mitchell 1991).
#include "best_candidate_tiles.h"

namespace lucent::points {

uint32_t placeTilePoints(const BestCandidateLevel& level, const Tile& tile, uint32_t colour, NeighbourRows& rows,
                         NeighbourList& nb) {
  const uint32_t c = level.candidates;
  // The neighbourhood: placed points of the 27 tiles, and the new points of neighbours done in
  // earlier phases.
  nb.clear();
  rows.forEach(tile.key, [&](const Tile& n) {
    for (uint32_t k = n.placedBegin; k < n.placedEnd; ++k) nb.add(level.placedByTile[k]);
    if (level.grid.colour(n.key) < colour)
      for (uint32_t k = pointsBefore(n.candBegin, c); k < pointsBefore(n.candEnd, c); ++k)
        nb.add(level.positions[level.placed + k]);
  });
  uint32_t few = 0;
  // Pieces (one triangle's run of candidates) in order; each point takes its share.
  for (uint32_t a = tile.candBegin; a < tile.candEnd;) {
    uint32_t b = a + 1;
    while (b < tile.candEnd && level.candidateKeys[b] == level.candidateKeys[a]) ++b;
    const uint32_t first = pointsBefore(a, c), pieceCount = pointsBefore(b, c) - first;
    const uint32_t m = b - a;
    for (uint32_t j = 0; j < pieceCount; ++j) {
      const uint32_t lo = a + uint32_t(uint64_t(j) * m / pieceCount);
      const uint32_t hi = a + uint32_t(uint64_t(j + 1) * m / pieceCount);
      float bestD2 = -1;
      PointSample best;
      Vec3 bestP;
      auto consider = [&](const PointSample& s, Vec3 p) {
        const float d2 = nb.nearest2(p, level.cap2);
        if (d2 > bestD2) bestD2 = d2, best = s, bestP = p;
      };
      for (uint32_t k = lo; k < hi; ++k) {
        const PointSample s = candidateOn(level.triangleOf(k), level.seed, level.level, level.candidateIndices[k]);
        consider(s, pointPosition(*level.scene, s));
      }
      // A piece too small for its share of c (a small triangle, or a corner of one in the tile):
      // more candidates uniform on the piece, by rejection from the triangle, up to c in all within
      // 4c tries. Counts stay as dealt, so area-proportionality holds.
      uint32_t have = hi - lo;
      for (uint32_t t = 0; have < c && t < kTopUpTries * c; ++t) {
        const PointSample s = topUpCandidate(level.triangleOf(a), level.seed, level.level, level.candidateIndices[lo], t);
        const Vec3 p = pointPosition(*level.scene, s);
        if (level.grid.keyOf(p) != tile.key) continue;
        consider(s, p);
        ++have;
      }
      few += 2 * have < c;
      level.points[level.placed + first + j] = best;
      level.positions[level.placed + first + j] = bestP;
      nb.add(bestP);
    }
    a = b;
  }
  return few;
}

}  // namespace lucent::points
