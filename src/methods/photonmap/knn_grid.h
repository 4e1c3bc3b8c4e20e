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
// out after every shell. Every grid map goes through GridPhotonMap (a template, no virtual calls);
// the hashed grid's entries of other cells are skipped here. Where the order of photons cannot
// change which are accepted, the maps that keep rows of cells as runs of their photon list (the
// sorted and stencil grids) read whole boxes and rows instead of shells: a search short of k
// (exploreShortSearch), the first shells while all their photons must be accepted (acceptedCube)
// and the shells after the k-th photon (exploreBeyondCube). They accept the same photons with the
// same radius as shell by shell; only where two accepted photons lie at exactly the farthest
// distance can the one met first, whose share the estimate leaves out, be another.
#pragma once
#include <algorithm>
#include <bit>
#include <concepts>
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
  uint32_t shells = 0;      // shells explored: 0 before the first call, 1 after the query's cell;
                            // a search that ends by reading its reach box (exploreShortSearch,
                            // exploreBeyondCube) counts every shell the box touches
  bool done = false;        // no unexplored photon can be accepted
  uint8_t boxesRead = 0;    // the parts of the search read as boxes of rows (KnnBoxRead bits)
  uint32_t cellsVisited = 0, photonsExamined = 0, collisionsSkipped = 0;  // counters
};
// Per-query state that a GPU would keep per pixel between passes.
static_assert(sizeof(KnnGridSearch) == 48 && std::is_trivially_copyable_v<KnnGridSearch>);

// Where the order cannot matter, the sorted and stencil grids read boxes of rows instead of shells
// (see above); a search records which of them it took, so that tests can see each one compared.
enum KnnBoxRead : uint8_t { kReadShortSearch = 1, kReadAcceptedCube = 2, kReadBeyondCube = 4 };

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
    if (ci[a] - s > 0) d = std::min(d, p[a] - g.cellLo(a, ci[a] - s));
    if (ci[a] + s + 1 < g.res[a]) d = std::min(d, g.cellLo(a, ci[a] + s + 1) - p[a]);
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

// The cells a sphere of squared radius limit2 about the query can reach. The acceptance radius
// takes two values in a search (the maximum radius while fewer than k are accepted, then the final
// one), so the box is computed when it changes, not for every shell.
struct Reach {
  float limit2 = -1;
  int32_t lo[3] = {}, hi[3] = {};  // set by the first update (limit2 is never negative)
  void update(const UniformGrid& g, Vec3 p, float newLimit2) {
    if (newLimit2 == limit2) return;
    limit2 = newLimit2;
    for (int a = 0; a < 3; ++a) reachAlong(g, p, limit2, a, lo[a], hi[a]);
  }
  // Every cell of the grid (the reach of an infinite radius).
  static Reach whole(const UniformGrid& g) {
    Reach r;
    r.limit2 = kInf;
    for (int a = 0; a < 3; ++a) r.lo[a] = 0, r.hi[a] = g.res[a] - 1;
    return r;
  }
};

inline float acceptanceLimit2(const KnnGridSearch& s) { return s.found < s.k ? s.maxRadius2 : s.radius2; }

// Offers photons to the running estimate in the order given. sumPhotonRun and growingRadius
// (photon_columns.cpp) apply the same rule eight photons at a time: keep the three in step.
template <class Visit>
void examinePhotons(const CellPhotons& cp, KnnGridSearch& s, Visit& visit) {
  auto otherCell = [&](uint32_t i) {  // another cell's photon in a hash bucket
    const bool other = cp.cellKeys && cp.cellKeys[i] != cp.cellKey;
    s.collisionsSkipped += other;
    return other;
  };
  uint32_t i = 0;
  // While fewer than k are accepted, any photon within the maximum radius is, and the radius grows
  // to include it.
  for (; i < cp.count && s.found < s.k; ++i) {
    if (otherCell(i)) continue;
    const float d2 = distance2(cp.photons[i].position, s.position);
    ++s.photonsExamined;
    if (!(d2 <= s.maxRadius2)) continue;
    s.radius2 = std::max(s.radius2, d2);
    ++s.found;
    visit(cp.ids[i], cp.photons[i], d2);
  }
  // Then the radius stays, and photons within it are accepted: distances by blocks, without a
  // branch per photon, then the accepted ones of the block in order.
  const Vec3 q = s.position;
  const float radius2 = s.radius2;
  constexpr uint32_t kBlock = 16;
  float d2[kBlock];
  while (i < cp.count) {
    const uint32_t n = std::min(kBlock, cp.count - i);
    uint32_t inside = 0;
    for (uint32_t j = 0; j < n; ++j) {
      d2[j] = distance2(cp.photons[i + j].position, q);
      inside |= uint32_t(d2[j] <= radius2) << j;
    }
    uint32_t others = 0;
    if (cp.cellKeys)
      for (uint32_t j = 0; j < n; ++j) others |= uint32_t(otherCell(i + j)) << j;
    inside &= ~others;
    s.photonsExamined += n - uint32_t(std::popcount(others));
    for (; inside; inside &= inside - 1) {
      const uint32_t j = uint32_t(std::countr_zero(inside));
      ++s.found;
      visit(cp.ids[i + j], cp.photons[i + j], d2[j]);
    }
    i += n;
  }
}

// Maps that keep a row of cells (and any range of cell indices) as one run of their photon list:
// the sorted and stencil grids, not the hashed grid.
template <class Map>
constexpr bool kReadsRuns = requires(const Map& map) {
  map.rowPhotons(0, 0, 0, 0);
  map.cellRangePhotons(0u, 0u);
};

// A visitor may take a run of photons whole (the radiance estimate of a Lambertian surface sums
// them from the map's columns, eight at a time: photon_columns.h) and answer true, having updated
// the search exactly as examinePhotons would; otherwise it sees them one by one.
template <class Visit>
void examineRun(const CellPhotons& cp, KnnGridSearch& s, Visit& visit) {
  if constexpr (requires { { visit.takeRun(cp, s) } -> std::same_as<bool>; })
    if (visit.takeRun(cp, s)) return;
  examinePhotons(cp, s, visit);
}

// A cell's photons, or a run of cells', examined as one cell visit; an empty run is no visit.
template <class Visit>
void visitRun(const CellPhotons& run, KnnGridSearch& s, Visit& visit) {
  if (run.count == 0) return;
  ++s.cellsVisited;
  examineRun(run, s, visit);
}

template <GridPhotonMap Map, class Visit>
void exploreCell(const Map& map, KnnGridSearch& s, CellCoord cell, Visit& visit) {
  const CellPhotons photons = map.cellPhotons(cell);
  if (photons.count == 0) return;
  if (map.grid.cellDistance2(s.position, cell) > acceptanceLimit2(s)) return;  // no photon in it can be accepted
  visitRun(photons, s, visit);
}

// Cells x0..x1 of the row (y, z) trimmed to those that the chord of the sphere of squared radius r2
// about p through the row reaches; false when none is left.
inline bool chordOfRow(const UniformGrid& g, Vec3 p, float r2, int32_t y, int32_t z, int32_t& x0, int32_t& x1) {
  const float dy = g.axisGap(1, y, p.y), dz = g.axisGap(2, z, p.z);
  const float rest = r2 - dy * dy - dz * dz;
  if (rest < 0) return false;
  const float half = std::sqrt(rest) * 1.00001f + g.slack;  // a margin far above the rounding of d2
  const float first = std::floor((p.x - half - g.lo[0]) * g.invCellSize[0]);
  const float last = std::floor((p.x + half - g.lo[0]) * g.invCellSize[0]);
  if (first > float(x0)) x0 = first > float(x1) ? x1 + 1 : int32_t(first);
  if (last < float(x1)) x1 = last < float(x0) ? x0 - 1 : int32_t(last);
  return x0 <= x1;
}

// A row of cells (x0..x1, y, z), first trimmed to the cells that the acceptance sphere's chord
// through the row reaches. Where the map keeps a row's photons contiguous in cell order (the sorted
// and stencil grids), they are read in one run: the same photons in the same order as cell by cell,
// without touching the empty cells (a photon in a cell that the acceptance sphere cannot reach is
// rejected by its own distance). The run counts as one cell visit.
template <GridPhotonMap Map, class Visit>
void exploreRow(const Map& map, KnnGridSearch& s, int32_t x0, int32_t x1, int32_t y, int32_t z, Visit& visit) {
  if constexpr (kReadsRuns<Map>) {
    // An empty row costs two loads, not a chord. (The run is read again after the chord trims it:
    // reusing this read where the chord trims nothing made the RING estimate 20% slower.)
    if (map.rowPhotons(x0, x1, y, z).count == 0) return;
  }
  const float limit2 = acceptanceLimit2(s);
  if (limit2 < kInf && !chordOfRow(map.grid, s.position, limit2, y, z, x0, x1)) return;
  if constexpr (kReadsRuns<Map>) {
    visitRun(map.rowPhotons(x0, x1, y, z), s, visit);
  } else {
    for (int32_t x = x0; x <= x1; ++x) exploreCell(map, s, {x, y, z}, visit);
  }
}

template <class Map>
constexpr bool kHasCellCounts = requires(const Map& map) { map.cellCounts.count(nullptr, nullptr); };

// Photons in the cells [lo, hi] if the map can count them; otherwise "maybe some" (1) for a box
// that has cells.
template <class Map>
uint32_t photonsIn(const Map& map, const int32_t lo[3], const int32_t hi[3]) {
  if constexpr (kHasCellCounts<Map>) return map.cellCounts.count(lo, hi);
  else return lo[0] <= hi[0] && lo[1] <= hi[1] && lo[2] <= hi[2] ? 1 : 0;
}

// The box of cells within Chebyshev distance `shell` of c (shells 0..shell), clipped to the reach
// box (Reach::whole: to the grid).
inline void shellBox(const Reach& reach, CellCoord c, int32_t shell, int32_t lo[3], int32_t hi[3]) {
  const int32_t ci[3] = {c.x, c.y, c.z};
  for (int a = 0; a < 3; ++a) lo[a] = std::max(reach.lo[a], ci[a] - shell), hi[a] = std::min(reach.hi[a], ci[a] + shell);
}

// Below this many rows, slabs or ends, a shell's parts are read directly (an empty row of a map
// with row runs costs two loads) rather than bisected on the cell counts (eight loads a count).
inline constexpr int32_t kBisectFrom = 4;

// The cells at Chebyshev distance exactly s from c, clipped to the grid and to the cells that the
// sphere of the current acceptance radius can reach, in z, y, x order. The shell is two z faces and,
// between them, slabs of two y rows and two x ends. Ranges of slabs, rows and ends that hold no
// photon are skipped by bisection on the map's cell counts, which keeps the order of the cells that
// hold some: a search through empty space costs a few lookups per shell, not one per cell.
template <GridPhotonMap Map, class Visit>
struct ShellExplorer {
  const Map& map;
  KnnGridSearch& s;
  Visit& visit;
  int32_t lo[3], hi[3];
  bool yLo, yHi, xLo, xHi;  // the shell's y rows and x ends lie within lo..hi
  int32_t yi0, yi1;         // y range of the x ends

  uint32_t photons(int32_t x0, int32_t x1, int32_t y0, int32_t y1, int32_t z0, int32_t z1) const {
    const int32_t boxLo[3] = {x0, y0, z0}, boxHi[3] = {x1, y1, z1};
    return photonsIn(map, boxLo, boxHi);
  }
  // Rows y0..y1 of the full-width face at z.
  void rows(int32_t y0, int32_t y1, int32_t z) {
    if constexpr (kReadsRuns<Map>) {
      if (y1 - y0 < kBisectFrom) {
        for (int32_t y = y0; y <= y1; ++y) exploreRow(map, s, lo[0], hi[0], y, z, visit);
        return;
      }
    }
    if (photons(lo[0], hi[0], y0, y1, z, z) == 0) return;
    if (y0 == y1) return exploreRow(map, s, lo[0], hi[0], y0, z, visit);
    const int32_t mid = y0 + (y1 - y0) / 2;
    rows(y0, mid, z), rows(mid + 1, y1, z);
  }
  uint32_t ends(int32_t y0, int32_t y1, int32_t z0, int32_t z1) const {
    return (xLo ? photons(lo[0], lo[0], y0, y1, z0, z1) : 0) + (xHi ? photons(hi[0], hi[0], y0, y1, z0, z1) : 0);
  }
  // The x ends of rows y0..y1 at z.
  void endCells(int32_t y0, int32_t y1, int32_t z) {
    if (y1 - y0 < kBisectFrom && kHasCellCounts<Map>) {
      for (int32_t y = y0; y <= y1; ++y) {
        if (xLo) exploreCell(map, s, {lo[0], y, z}, visit);
        if (xHi) exploreCell(map, s, {hi[0], y, z}, visit);
      }
      return;
    }
    if (ends(y0, y1, z, z) == 0) return;
    if (y0 == y1) {
      if (xLo) exploreCell(map, s, {lo[0], y0, z}, visit);
      if (xHi) exploreCell(map, s, {hi[0], y0, z}, visit);
      return;
    }
    const int32_t mid = y0 + (y1 - y0) / 2;
    endCells(y0, mid, z), endCells(mid + 1, y1, z);
  }
  // The slabs z0..z1 between the z faces.
  void slabs(int32_t z0, int32_t z1) {
    if (z1 - z0 < kBisectFrom && kHasCellCounts<Map>) {
      for (int32_t z = z0; z <= z1; ++z) {
        if (yLo) rows(lo[1], lo[1], z);
        if (yi0 <= yi1) endCells(yi0, yi1, z);
        if (yHi) rows(hi[1], hi[1], z);
      }
      return;
    }
    const uint32_t n = (yLo ? photons(lo[0], hi[0], lo[1], lo[1], z0, z1) : 0) +
                       (yHi ? photons(lo[0], hi[0], hi[1], hi[1], z0, z1) : 0) + ends(yi0, yi1, z0, z1);
    if (n == 0) return;
    if (z0 == z1) {
      if (yLo) rows(lo[1], lo[1], z0);
      if (yi0 <= yi1) endCells(yi0, yi1, z0);
      if (yHi) rows(hi[1], hi[1], z0);
      return;
    }
    const int32_t mid = z0 + (z1 - z0) / 2;
    slabs(z0, mid), slabs(mid + 1, z1);
  }
};

template <GridPhotonMap Map, class Visit>
void exploreShell(const Map& map, KnnGridSearch& s, const Reach& reach, CellCoord c, int32_t shell, Visit& visit) {
  ShellExplorer<Map, Visit> e{map, s, visit, {}, {}, false, false, false, false, 0, 0};
  shellBox(reach, c, shell, e.lo, e.hi);
  const int32_t* lo = e.lo;
  const int32_t* hi = e.hi;
  const bool zLo = c.z - shell == lo[2], zHi = c.z + shell == hi[2] && shell > 0;
  e.yLo = c.y - shell == lo[1], e.yHi = c.y + shell == hi[1] && shell > 0;
  e.xLo = c.x - shell == lo[0], e.xHi = c.x + shell == hi[0] && shell > 0;
  e.yi0 = lo[1] + e.yLo, e.yi1 = hi[1] - e.yHi;
  if (zLo) e.rows(lo[1], hi[1], lo[2]);
  if (lo[2] + zLo <= hi[2] - zHi) e.slabs(lo[2] + zLo, hi[2] - zHi);
  if (zHi) e.rows(lo[1], hi[1], hi[2]);
}

// The last shell about c that the reach box touches.
inline int32_t lastShellOf(const Reach& reach, CellCoord c) {
  const int32_t ci[3] = {c.x, c.y, c.z};
  int32_t last = 0;
  for (int a = 0; a < 3; ++a) last = std::max({last, ci[a] - reach.lo[a], reach.hi[a] - ci[a]});
  return last;
}

// Shells from `shell` on that hold no photon the acceptance sphere can reach, found by bisection on
// the map's cell counts (the acceptance radius does not change while nothing is accepted): 0 if
// shell `shell` holds some, kAllEmpty if every unexplored cell within reach is empty.
inline constexpr uint32_t kAllEmpty = UINT32_MAX;
template <GridPhotonMap Map>
uint32_t emptyShellsFrom(const Map& map, const Reach& reach, CellCoord c, int32_t shell) {
  if constexpr (!kHasCellCounts<Map>) {
    return 0;
  } else {
    int32_t lo[3], hi[3];
    auto withinShells = [&](int32_t t) {  // photons within reach in shells 0..t
      if (t < 0) return 0u;
      shellBox(reach, c, t, lo, hi);
      return map.cellCounts.count(lo, hi);
    };
    const uint32_t explored = withinShells(shell - 1);
    if (withinShells(shell) != explored) return 0;  // the common case next to photons
    if (map.cellCounts.count(reach.lo, reach.hi) == explored) return kAllEmpty;
    // The first shell whose cube covers the reach box holds the rest: bisect below it.
    int32_t emptyUpTo = shell, nonEmpty = lastShellOf(reach, c);  // invariant: shells shell..emptyUpTo empty
    while (nonEmpty - emptyUpTo > 1) {
      const int32_t mid = emptyUpTo + (nonEmpty - emptyUpTo) / 2;
      (withinShells(mid) == explored ? emptyUpTo : nonEmpty) = mid;
    }
    return uint32_t(emptyUpTo - shell + 1);
  }
}

// The longest run of photons read at once to settle a search that cannot reach k.
inline constexpr uint32_t kShortSearchRun = 256;

// A search that cannot reach k photons (the reach box of the maximum radius holds fewer than the
// k - found still sought) accepts every photon within the maximum radius, in any order. Where the
// photon list from the reach box's first cell to its last is short, it is read as one run: the
// photons between them that lie in cells outside the box are beyond the maximum radius and
// rejected by their distance. This spares the shells to the maximum radius in dark regions (RING's
// global map holds 12 photons; each of its queries used to walk some 40 shells' counts). Returns
// whether the search is settled.
template <GridPhotonMap Map, class Visit>
bool exploreShortSearch(const Map& map, KnnGridSearch& s, const Reach& reach, Visit& visit) {
  if (map.cellCounts.count(reach.lo, reach.hi) >= s.k - s.found) return false;
  for (int a = 0; a < 3; ++a)
    if (reach.lo[a] > reach.hi[a]) return true;  // no cell within reach
  const UniformGrid& g = map.grid;
  const CellPhotons run = map.cellRangePhotons(g.cellIndex({reach.lo[0], reach.lo[1], reach.lo[2]}),
                                               g.cellIndex({reach.hi[0], reach.hi[1], reach.hi[2]}));
  if (run.count > kShortSearchRun) return false;
  visitRun(run, s, visit);
  return true;
}

// The shells that can be taken together as one box, row by row, because the order of their
// photons cannot matter: they hold fewer photons than the k - found still sought, and all lie
// within the maximum radius (the box's farthest corner does, the box cut to the photons' bounds),
// so every one of them is accepted under the growing radius whatever the order, and the radius
// after them is their farthest photon's. The search after them is that of shell by shell. It
// saves the piecewise walk through the dozen sparse shells that a fine grid (the paper's
// 250 x 1 x 250) needs before k photons are met. Returns the last such shell t (at most `most`),
// or -1 where shell 0 alone does not qualify.
template <GridPhotonMap Map>
int32_t acceptedCube(const Map& map, const KnnGridSearch& s, CellCoord c, int32_t most) {
  const UniformGrid& g = map.grid;
  const Reach grid = Reach::whole(g);
  auto qualifies = [&](int32_t t) {  // the box of shells 0..t
    int32_t lo[3], hi[3];
    shellBox(grid, c, t, lo, hi);
    float far2 = 0;
    for (int a = 0; a < 3; ++a) {
      const float boxLo = g.cellLo(a, lo[a]) - g.slack;
      const float boxHi = std::min(g.cellLo(a, hi[a] + 1), g.hi[a]) + g.slack;
      const float far = std::max(s.position[a] - boxLo, boxHi - s.position[a]);
      far2 += far * far;
    }
    // The margin covers the rounding of far2 and of each photon's distance2.
    return far2 * 1.0001f <= s.maxRadius2 && map.cellCounts.count(lo, hi) < s.k - s.found;
  };
  if (most < 0 || !qualifies(0)) return -1;
  int32_t yes = 0, no = std::min(most, lastShellOf(grid, c)) + 1;  // shells 0..lastShellOf cover the grid
  while (no - yes > 1) {
    const int32_t mid = yes + (no - yes) / 2;
    (qualifies(mid) ? yes : no) = mid;
  }
  return yes;
}

// Every row of the box of shells 0..t, each one run.
template <GridPhotonMap Map, class Visit>
void exploreCube(const Map& map, KnnGridSearch& s, CellCoord c, int32_t t, Visit& visit) {
  int32_t lo[3], hi[3];
  shellBox(Reach::whole(map.grid), c, t, lo, hi);  // the box of shells 0..t
  for (int32_t z = lo[2]; z <= hi[2]; ++z)
    for (int32_t y = lo[1]; y <= hi[1]; ++y) visitRun(map.rowPhotons(lo[0], hi[0], y, z), s, visit);
}

// Once k photons are accepted the radius stays, and the photons within it are accepted in any
// order. The shells beyond the explored ones (0..t), out to the last that the sphere reaches, are
// then read as the rows of the reach box outside the cube of shells 0..t: one run per row, or two
// where the row passes through the cube. The same photons as shell by shell, in fewer and longer
// runs.
template <GridPhotonMap Map, class Visit>
void exploreBeyondCube(const Map& map, KnnGridSearch& s, const Reach& reach, CellCoord c, int32_t t, Visit& visit) {
  int32_t lo[3], hi[3];
  shellBox(Reach::whole(map.grid), c, t, lo, hi);  // the cube of shells 0..t
  for (int32_t z = reach.lo[2]; z <= reach.hi[2]; ++z)
    for (int32_t y = reach.lo[1]; y <= reach.hi[1]; ++y) {
      if (y < lo[1] || y > hi[1] || z < lo[2] || z > hi[2]) {
        exploreRow(map, s, reach.lo[0], reach.hi[0], y, z, visit);
        continue;
      }
      if (reach.lo[0] < lo[0]) exploreRow(map, s, reach.lo[0], lo[0] - 1, y, z, visit);
      if (hi[0] < reach.hi[0]) exploreRow(map, s, hi[0] + 1, reach.hi[0], y, z, visit);
    }
}


}  // namespace knn_grid_detail

// Explores up to `shells` more shells, calling visit(photonIndex, photon, d2) for every photon
// accepted (photonIndex into map.photons, in the order of the input photons), unless the visitor
// takes a run whole (examineRun). Where boxes of rows are read, photons come in another order than
// shell by shell (see the top of this file).
template <GridPhotonMap Map, class Visit>
void advanceKnnGrid(const Map& map, KnnGridSearch& s, uint32_t shells, Visit&& visit) {
  using namespace knn_grid_detail;
  const UniformGrid& g = map.grid;
  const CellCoord c = g.cellOf(s.position);
  Reach reach;
  for (uint32_t i = 0; i < shells && !s.done;) {
    uint32_t step = 0;
    if constexpr (kReadsRuns<Map> && kHasCellCounts<Map>) {
      if (s.shells == 0) {
        reach.update(g, s.position, acceptanceLimit2(s));
        const uint32_t lastShell = uint32_t(lastShellOf(reach, c));
        if (lastShell < shells && exploreShortSearch(map, s, reach, visit)) {
          s.shells = lastShell + 1;
          s.done = true;
          s.boxesRead |= kReadShortSearch;
          break;
        }
        const int32_t cube = acceptedCube(map, s, c, int32_t(std::min<uint32_t>(shells, INT32_MAX) - 1));
        if (cube >= 0) {
          exploreCube(map, s, c, cube, visit);
          step = uint32_t(cube) + 1;
          s.boxesRead |= kReadAcceptedCube;
        }
      }
    }
    if (step == 0) {
      reach.update(g, s.position, acceptanceLimit2(s));
      // Empty shells are explored by skipping them; a non-empty one cell by cell.
      const uint32_t empty = emptyShellsFrom(map, reach, c, int32_t(s.shells));
      if (empty == kAllEmpty) {
        s.done = true;
        break;
      }
      step = empty > 0 ? std::min(empty, shells - i) : 1;
      if (empty == 0) exploreShell(map, s, reach, c, int32_t(s.shells), visit);
    }
    s.shells += step, i += step;
    const float beyond = distanceBeyondShell(g, s.position, c, int32_t(s.shells) - 1);
    const float beyond2 = beyond > 0 ? beyond * beyond : 0;
    s.done = beyond == kInf || beyond2 > s.maxRadius2 || (s.found >= s.k && beyond2 > s.radius2);
    if constexpr (kReadsRuns<Map>) {
      if (!s.done && s.found >= s.k) {
        reach.update(g, s.position, s.radius2);
        const int32_t last = lastShellOf(reach, c);
        if (uint32_t(last + 1) - s.shells <= shells - i) {  // the search's end within this call's shells
          exploreBeyondCube(map, s, reach, c, int32_t(s.shells) - 1, visit);
          i += uint32_t(last + 1) - s.shells;
          s.shells = uint32_t(last + 1);
          s.done = true;
          s.boxesRead |= kReadBeyondCube;
        }
      }
    }
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
