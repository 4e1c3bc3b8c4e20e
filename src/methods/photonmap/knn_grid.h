// The kNN-grid search (Purcell et al. 2003, section 2.3, Fig. 6): a variant of Cleary's (Elias's)
// k-nearest-neighbour search in a uniform grid, used for the radiance estimate.
//
// Cells are explored in concentric shells about the query's cell: shell s holds the cells at
// Chebyshev distance s (in cells) from it, so shell 0 is the query's cell alone. A photon beyond the
// maximum radius is always rejected. While fewer than k photons are accepted, any other photon is
// accepted and the search radius grows to include it; afterwards the radius stays, and photons within
// it are accepted, the rest rejected. The search ends after a shell when nothing unexplored can lie
// within reach: the distance from the query to the unexplored cells exceeds the maximum radius, or
// at least k photons are accepted and it exceeds the search radius (or every cell is explored).
//
// Every accepted photon lies within the final radius and every photon within it is accepted: the
// result is all photons in a sphere, at least k of them unless fewer lie within the maximum radius,
// over a radius at least as large as the k-th nearest photon's (the paper's "at least k nearest").
//
// The search is resumable: advanceKnnGrid explores a given number of shells and returns, leaving the
// state of the running estimate, so that the progressive result the paper displays can be written
// out after every shell. One code path serves every grid map through GridPhotonMap (a template, no
// virtual calls); the hashed grid's entries of other cells are skipped here.
#pragma once
#include <algorithm>
#include <cstdint>
#include <type_traits>

#include "uniform_grid.h"

namespace lucent {

struct KnnGridSearch {
  Vec3 position;            // the query point
  uint32_t k = 0;           // photons sought
  float maxRadius2 = 0;     // squared maximum search radius
  float radius2 = 0;        // squared search radius so far (see knnGridRadius2 for the estimate's)
  uint32_t found = 0;       // photons accepted into the running estimate
  uint32_t shells = 0;      // shells explored: 0 before the first call, 1 after the query's cell
  bool done = false;        // no unexplored photon can be accepted
  uint32_t cellsVisited = 0, photonsExamined = 0, collisionsSkipped = 0;  // counters
};
// Per-query state that a GPU would keep per pixel between passes.
static_assert(sizeof(KnnGridSearch) == 48 && std::is_trivially_copyable_v<KnnGridSearch>);

inline KnnGridSearch beginKnnGrid(Vec3 position, uint32_t k, float maxRadius) {
  KnnGridSearch s;
  s.position = position;
  s.k = k;
  s.maxRadius2 = maxRadius * maxRadius;
  return s;
}

// The squared radius of the radiance estimate: the search radius, or the maximum radius once the
// search has ended with fewer than k photons (all photons in that sphere were found: Jensen 2001).
inline float knnGridRadius2(const KnnGridSearch& s) {
  return s.done && s.found < s.k ? s.maxRadius2 : s.radius2;
}

namespace knn_grid_detail {

// Distance from p to the cells beyond shells 0..s about c (those at Chebyshev distance > s), less
// the grid's slack; infinite when there are none.
inline float distanceBeyondShell(const UniformGrid& g, Vec3 p, CellCoord c, int32_t s) {
  float d = kInf;
  const int32_t ci[3] = {c.x, c.y, c.z};
  for (int a = 0; a < 3; ++a) {
    if (ci[a] - s > 0) d = std::min(d, p[a] - (g.lo[a] + float(ci[a] - s) * g.cellSize[a]));
    if (ci[a] + s + 1 < g.res[a]) d = std::min(d, g.lo[a] + float(ci[a] + s + 1) * g.cellSize[a] - p[a]);
  }
  return d - g.slack;
}

// Cells [lo, hi] along axis a that a sphere of squared radius r2 about p can reach.
inline void reachAlong(const UniformGrid& g, Vec3 p, float r2, int a, int32_t& lo, int32_t& hi) {
  lo = 0, hi = g.res[a] - 1;
  if (!(r2 < kInf)) return;
  const float r = std::sqrt(r2) + g.slack;
  const float first = std::floor((p[a] - r - g.lo[a]) * g.invCellSize[a]) - 1;
  const float last = std::floor((p[a] + r - g.lo[a]) * g.invCellSize[a]) + 1;
  if (first > float(lo)) lo = first > float(hi) ? hi + 1 : int32_t(first);
  if (last < float(hi)) hi = last < float(lo) ? lo - 1 : int32_t(last);
}

template <GridPhotonMap Map, class Visit>
void exploreCell(const Map& map, KnnGridSearch& s, CellCoord cell, Visit& visit) {
  const float limit2 = s.found < s.k ? s.maxRadius2 : s.radius2;
  if (map.grid.cellDistance2(s.position, cell) > limit2) return;  // no photon in it can be accepted
  ++s.cellsVisited;
  const CellPhotons cp = map.cellPhotons(cell);
  const Photon* photons = map.photons.data();
  for (uint32_t i = 0; i < cp.count; ++i) {
    if (cp.cellKeys && cp.cellKeys[i] != cp.cellKey) {  // another cell's photon in the bucket
      ++s.collisionsSkipped;
      continue;
    }
    const Photon& photon = photons[cp.ids[i]];
    const float d2 = distance2(photon.position, s.position);
    ++s.photonsExamined;
    if (s.found < s.k) {
      if (d2 > s.maxRadius2) continue;
      s.radius2 = std::max(s.radius2, d2);  // expand the radius to include the photon
    } else if (d2 > s.radius2) {
      continue;
    }
    ++s.found;
    visit(cp.ids[i], photon, d2);
  }
}

// The cells at Chebyshev distance exactly s from c, clipped to the grid and to the cells that the
// sphere of the current acceptance radius can reach.
template <GridPhotonMap Map, class Visit>
void exploreShell(const Map& map, KnnGridSearch& s, CellCoord c, int32_t shell, Visit& visit) {
  const UniformGrid& g = map.grid;
  const float limit2 = s.found < s.k ? s.maxRadius2 : s.radius2;
  int32_t lo[3], hi[3];
  for (int a = 0; a < 3; ++a) reachAlong(g, s.position, limit2, a, lo[a], hi[a]);
  const int32_t x0 = std::max(c.x - shell, lo[0]), x1 = std::min(c.x + shell, hi[0]);
  for (int32_t z = std::max(c.z - shell, lo[2]); z <= std::min(c.z + shell, hi[2]); ++z)
    for (int32_t y = std::max(c.y - shell, lo[1]); y <= std::min(c.y + shell, hi[1]); ++y) {
      if (std::abs(z - c.z) == shell || std::abs(y - c.y) == shell) {  // a face of the shell: whole row
        for (int32_t x = x0; x <= x1; ++x) exploreCell(map, s, {x, y, z}, visit);
      } else {  // inside the shell's box: only its two ends
        if (c.x - shell >= lo[0]) exploreCell(map, s, {c.x - shell, y, z}, visit);
        if (c.x + shell <= hi[0]) exploreCell(map, s, {c.x + shell, y, z}, visit);
      }
    }
}

}  // namespace knn_grid_detail

// Explores up to `shells` more shells, calling visit(photonIndex, photon, d2) for every photon
// accepted (photonIndex into map.photons, in the order of the input photons).
template <GridPhotonMap Map, class Visit>
void advanceKnnGrid(const Map& map, KnnGridSearch& s, uint32_t shells, Visit&& visit) {
  using namespace knn_grid_detail;
  const UniformGrid& g = map.grid;
  const CellCoord c = g.cellOf(s.position);
  for (uint32_t i = 0; i < shells && !s.done; ++i) {
    exploreShell(map, s, c, int32_t(s.shells), visit);
    const float beyond = distanceBeyondShell(g, s.position, c, int32_t(s.shells));
    ++s.shells;
    const float beyond2 = beyond > 0 ? beyond * beyond : 0;
    s.done = beyond == kInf || beyond2 > s.maxRadius2 || (s.found >= s.k && beyond2 > s.radius2);
  }
}

// The whole search.
template <GridPhotonMap Map, class Visit>
KnnGridSearch knnGrid(const Map& map, Vec3 position, uint32_t k, float maxRadius, Visit&& visit) {
  KnnGridSearch s = beginKnnGrid(position, k, maxRadius);
  advanceKnnGrid(map, s, UINT32_MAX, visit);
  return s;
}

}  // namespace lucent
