// Every shading point's radiance estimate from one map, as one data-parallel stage.
//
// On the sorted and stencil grids the points are taken cell by cell. The kNN-grid search (Purcell
// et al. 2003, 2.3) explores the same shells, in the same order, for every query in a cell; only the
// distances differ. While fewer than k photons are accepted, every photon met within the maximum
// radius is accepted, so a query's first k photons within its maximum radius, in its cell's shell
// order, are the k its search accepts first, and the radius is the farthest of them. The search
// then accepts every photon within that radius, and nothing else: the estimate is a sum over a
// sphere. A cell's photons are met once, in shell order (ShellOrder), as far as its queries need;
// each query's radius comes from them (growingRadius), and its sphere is summed from the rows of
// cells that it reaches (sumWithinRadius). A query that is not Lambertian, a search stopped after a
// number of shells, or a query whose k photons within its maximum radius lie beyond what its cell
// records takes the search of knn_grid.h instead. Both give the same photons, radius and estimate,
// up to the order of the power sums (and, where two of the first k photons lie at exactly the
// farthest distance, which one's share is left out: the first in the order recorded here, which
// reads a cell's sparse first shells as one box, possibly another there).
//
// The hashed grid and the kd-tree estimate point by point.
#pragma once
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <functional>
#include <span>
#include <vector>

#include "bitonic_sort.h"
#include "lucent/core/stop.h"
#include "lucent/pipeline/shading_points.h"
#include "lucent/core/parallel.h"
#include "radiance_estimate.h"

namespace lucent {

namespace cell_estimate_detail {

// A cell's shells in search order, recorded as the runs of the photon list the search would read.
struct RunRecorder {
  std::vector<CellPhotons>& runs;
  void operator()(uint32_t, const Photon&, float) {}  // unused: every run is taken whole
  bool takeRun(const CellPhotons& run, KnnGridSearch& s) {
    runs.push_back(run);
    s.found += run.count;
    return true;
  }
};

// The distance from any point of cell c to the cells beyond its shells 0..t, less the grid's slack
// (infinite when there are none).
inline float gapBeyondShell(const UniformGrid& g, CellCoord c, int32_t t) {
  const int32_t ci[3] = {c.x, c.y, c.z};
  float gap = kInf;
  for (int a = 0; a < 3; ++a)
    if (ci[a] - t > 0 || ci[a] + t + 1 < g.res[a]) gap = std::min(gap, float(t) * g.cellSize[a]);
  return gap - g.slack;
}

// The photons of one cell's shells in search order, copied as columns, recorded shell by shell as
// far as its queries need.
struct ShellOrder {
  std::vector<CellPhotons> runs;
  PhotonColumns photons;
  uint32_t recorded = 0;  // photons copied
  CellCoord cell;
  int32_t nextShell = 0;
  uint32_t k = 0;
  bool covers = false;  // every photon within the maximum radius of any point of the cell is recorded

  template <class Map>
  void begin(const Map& map, CellCoord c, uint32_t k, float maxRadius) {
    cell = c, nextShell = 0, recorded = 0, covers = false;
    this->k = k;
    // Where the cells within the maximum radius of the cell hold fewer than k photons, its
    // searches accept every photon within their maximum radius in any order: the photon list from
    // the first of those cells to the last, where short, holds them all (the photons in it from
    // other cells lie beyond the maximum radius): knn_grid.h's exploreShortSearch, over the reach
    // of the whole cell instead of one query's.
    const UniformGrid& g = map.grid;
    knn_grid_detail::Reach reach;
    const int32_t ci[3] = {c.x, c.y, c.z};
    for (int a = 0; a < 3; ++a) {  // compared as floats: the reach may exceed any integer
      const float cells = std::ceil((maxRadius + g.slack) * g.invCellSize[a]) + 1;
      reach.lo[a] = cells >= float(ci[a]) ? 0 : ci[a] - int32_t(cells);
      reach.hi[a] = cells >= float(g.res[a] - 1 - ci[a]) ? g.res[a] - 1 : ci[a] + int32_t(cells);
    }
    runs.clear();
    RunRecorder record{runs};
    KnnGridSearch s = beginKnnGrid(Vec3(), k, kInf);
    if (!knn_grid_detail::exploreShortSearch(map, s, reach, record)) return;
    recorded = runs.empty() ? 0 : runs.front().count;  // an empty run is not recorded
    resizeColumns(photons, recorded);
    if (recorded > 0) copyColumns(*runs.front().columns, runs.front().first, recorded, photons, 0);
    covers = true;
  }
  // Records shells until at least `want` photons are recorded or it covers the maximum radius.
  template <class Map>
  void extend(const Map& map, uint32_t want, float maxRadius) {
    using namespace knn_grid_detail;
    const UniformGrid& g = map.grid;
    runs.clear();
    KnnGridSearch s = beginKnnGrid(Vec3(), UINT32_MAX, kInf);  // no radius: every run met is recorded
    s.found = recorded;
    RunRecorder record{runs};
    const Reach whole = Reach::whole(g);
    if (nextShell == 0) {
      // The shells that hold fewer than k photons between them: every query accepts all of those
      // within its maximum radius before its k-th, in whatever order, so they are met as the rows
      // of their box, not shell by shell (knn_grid.h's acceptedCube, here with no maximum radius:
      // the count alone decides). Sparse regions need a dozen shells before k photons.
      const int32_t cube = acceptedCube(map, beginKnnGrid(Vec3(), k, kInf), cell, INT32_MAX);
      if (cube >= 0) {
        exploreCube(map, s, cell, cube, record);
        nextShell = cube + 1;
        covers = gapBeyondShell(g, cell, cube) > maxRadius || cube >= lastShellOf(whole, cell);
      }
    }
    while (s.found < want && !covers) {
      if (gapBeyondShell(g, cell, nextShell - 1) > maxRadius) {
        covers = true;
        break;
      }
      const uint32_t empty = emptyShellsFrom(map, whole, cell, nextShell);
      if (empty == kAllEmpty) {
        covers = true;
        break;
      }
      if (empty > 0) {
        nextShell += int32_t(empty);
        continue;
      }
      exploreShell(map, s, whole, cell, nextShell++, record);
    }
    resizeColumns(photons, s.found);
    for (const CellPhotons& run : runs) {
      copyColumns(*run.columns, run.first, run.count, photons, recorded);
      recorded += run.count;
    }
  }
};

// The runs of the map's photon list that hold every photon within squared radius r2 of p: the rows
// of cells that the sphere reaches, each trimmed to the sphere's chord as exploreRow trims it.
template <class Map>
void sphereRows(const Map& map, Vec3 p, float r2, std::vector<ColumnRun>& rows) {
  knn_grid_detail::Reach reach;
  reach.update(map.grid, p, r2);
  rows.clear();
  for (int32_t z = reach.lo[2]; z <= reach.hi[2]; ++z)
    for (int32_t y = reach.lo[1]; y <= reach.hi[1]; ++y) {
      int32_t x0 = reach.lo[0], x1 = reach.hi[0];
      if (!knn_grid_detail::chordOfRow(map.grid, p, r2, y, z, x0, x1)) continue;
      const CellPhotons run = map.rowPhotons(x0, x1, y, z);
      if (run.count > 0) rows.push_back({run.first, run.count});
    }
}

// The map whose rows a sphere's photons are summed from: the map itself, or the stencil grid's
// finer sorted grid of the same photons.
template <class Map>
const auto& sumGridOf(const Map& map) {
  if constexpr (requires { map.sumGrid; }) return map.sumGrid;
  else return map;
}

// What the estimate reads of a shading point, gathered in cell order.
struct CellQuery {
  Vec3 position;
  SurfaceSide side;
  Rgb kd;
  uint32_t point;    // index of the shading point
  uint32_t diffuse;  // 1 for a Lambertian surface; others are searched one by one
};
static_assert(sizeof(CellQuery) == 56);

// The relative costs of summing a photon and of finding a row's bounds (RING, 2 threads).
inline constexpr float kPhotonCost = 1, kRowCost = 64;
// A query whose maximum radius passes over some of its cell's first k photons reads the cell's
// shells on to this many times k photons (or to the maximum radius) before searching on its own.
inline constexpr uint32_t kFurtherShells = 8;

// The points' indices ordered by their cell, then index; groupStart: where each cell's begin, and
// the end. A counting sort where the grid has few cells beside the points, else a parallel sort.
inline void pointsByCell(const UniformGrid& g, std::span<const ShadingPoint> points, std::vector<uint32_t>& order,
                         std::vector<uint32_t>& groupStart) {
  const size_t n = points.size();
  std::vector<uint32_t> cellOfPoint(n);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, kItemsPerTask), [&](const tbb::blocked_range<size_t>& r) {
    stopPoint();
    for (size_t i = r.begin(); i != r.end(); ++i) cellOfPoint[i] = g.cellIndex(g.cellOf(points[i].position));
  });
  order.resize(n);
  groupStart.clear();
  if (g.cellCount() <= 4 * uint64_t(n)) {
    std::vector<uint32_t> next(g.cellCount() + 1, 0);
    for (uint32_t cell : cellOfPoint) ++next[cell + 1];
    for (size_t c = 1; c < next.size(); ++c) {
      if (next[c] > 0) groupStart.push_back(next[c - 1]);
      next[c] += next[c - 1];
    }
    for (size_t i = 0; i < n; ++i) order[next[cellOfPoint[i]]++] = uint32_t(i);
  } else {
    std::vector<uint64_t> keys(n);
    for (size_t i = 0; i < n; ++i) keys[i] = packSortKey(cellOfPoint[i], uint32_t(i));
    tbb::parallel_sort(keys.begin(), keys.end());
    for (size_t j = 0; j < n; ++j) {
      order[j] = sortIndexOf(keys[j]);
      if (j == 0 || sortKeyOf(keys[j]) != sortKeyOf(keys[j - 1])) groupStart.push_back(uint32_t(j));
    }
  }
  groupStart.push_back(uint32_t(n));
}

// What becomes of a query of a cell: its own search, a sphere of the radius its cell's photons
// set, or estimated already (fewer than k photons within its maximum radius).
struct QueryPlan {
  GrowingRadius radius;
  enum How : uint8_t { Search, Sphere, Done } how = Search;
};

struct Scratch {
  ShellOrder order;
  std::vector<QueryPlan> plans;
  std::vector<ColumnRun> rows, ownRows;  // the rows of a cell's box; one sphere's own
  std::vector<PhotonDistance> heap;
};

// What the spheres of a cell's queries reach together, and the cost of the first one's own rows.
struct CellReach {
  float lo[3] = {kInf, kInf, kInf}, hi[3] = {-kInf, -kInf, -kInf};
  uint32_t spheres = 0;
  float ownCost = 0;  // of reading a sphere's own rows
};

// Each query's radius from the cell's shell order (s.order, begun at the cell), and the extent
// that the spheres reach; queries settled on the way (nothing within reach, or fewer than k photons
// in all) get their estimate in `out` now.
template <class Map>
CellReach planCellQueries(const Map& map, std::span<const CellQuery> cell, const EstimateSettings& settings, Scratch& s,
                          EstimateCounters& c, std::span<Rgb> out) {
  using estimate_detail::diffuseRadiance;
  const auto& sums = sumGridOf(map);
  const uint32_t k = settings.k;
  const float maxRadius2 = settings.maxRadius * settings.maxRadius;
  CellReach reach;
  for (size_t j = 0; j < cell.size(); ++j) {
    const CellQuery& q = cell[j];
    QueryPlan& plan = s.plans[j];
    plan = {{}, QueryPlan::Search};
    if (!q.diffuse) continue;
    GrowingRadius& radius = plan.radius;
    radius = growingRadius(s.order.photons, s.order.recorded, q.position, q.side, maxRadius2, k);
    if (radius.found < k && !s.order.covers) {
      // Some of the cell's first photons lie beyond this query's maximum radius. None
      // within it (a point far outside the grid, its cell clamped): nothing to sum.
      knn_grid_detail::Reach cells;
      cells.update(map.grid, q.position, maxRadius2);
      if (map.cellCounts.count(cells.lo, cells.hi) == 0) {
        out[q.point] = Rgb();
        plan.how = QueryPlan::Done;
        ++c.queries;
        continue;
      }
      // Otherwise the cell records further (always to the same length, so that what a query
      // sees depends on its cell alone).
      const uint32_t further = uint32_t(std::min<uint64_t>(uint64_t(kFurtherShells) * k, UINT32_MAX));
      if (s.order.recorded < further) {  // else an earlier query extended it: radius has seen it all
        s.order.extend(map, further, settings.maxRadius);
        radius = growingRadius(s.order.photons, s.order.recorded, q.position, q.side, maxRadius2, k);
      }
    }
    if (radius.found < k) {
      // Fewer than k within the maximum radius, every one recorded: the search accepts them
      // all, over the maximum radius (Jensen's convention).
      if (!s.order.covers) continue;
      const ColumnRun all{0, s.order.recorded};
      const SphereSum sphere = sumWithinRadius(s.order.photons, {&all, 1}, q.position, q.side, maxRadius2);
      if (sphere.farthestD2 == maxRadius2) continue;  // one exactly on it: its share as the search leaves it out
      out[q.point] = diffuseRadiance(sphere.sum, q.kd, maxRadius2);
      plan.how = QueryPlan::Done;
      ++c.queries;
      c.photonsUsed += sphere.used;
      c.photonsExamined += s.order.recorded;
      continue;
    }
    plan.how = QueryPlan::Sphere;
    // The cells the sphere reaches, as exploreRow bounds a row by the sphere's chord.
    const float extent = std::sqrt(radius.d2) * 1.00001f + sums.grid.slack;
    const Vec3 sphereLo = q.position - Vec3(extent), sphereHi = q.position + Vec3(extent);
    for (int a = 0; a < 3; ++a)
      reach.lo[a] = std::min(reach.lo[a], sphereLo[a]), reach.hi[a] = std::max(reach.hi[a], sphereHi[a]);
    if (reach.spheres++ > 0) continue;
    // The first sphere's own rows stand for the others' (their radii differ little).
    const CellCoord l = sums.grid.cellOf(sphereLo), h = sums.grid.cellOf(sphereHi);
    const int32_t boxLo[3] = {l.x, l.y, l.z}, boxHi[3] = {h.x, h.y, h.z};
    reach.ownCost =
        kPhotonCost * float(sums.cellCounts.count(boxLo, boxHi)) + kRowCost * float((h.y - l.y + 1) * (h.z - l.z + 1));
  }
  return reach;
}

// The planned queries' sums.
template <class Map>
void sumCellQueries(const Map& map, std::span<const CellQuery> cell, std::span<const ShadingPoint> points,
                    const EstimateSettings& settings, const CellReach& reach, Scratch& s, EstimateCounters& c,
                    std::span<Rgb> out) {
  using estimate_detail::diffuseRadiance;
  const auto& sums = sumGridOf(map);
  // Each sphere reads either the rows of the box of cells that the cell's spheres reach
  // together (found once; where the cells are small beside the spheres, that box is little
  // larger than each sphere's) or its own rows trimmed to its chords, whichever holds fewer
  // photons. Both give the same sums (sumWithinRadius), so a query's estimate does not
  // depend on the other points in its cell.
  s.rows.clear();
  bool boxRows = false;
  if (reach.spheres > 0) {
    const CellCoord l = sums.grid.cellOf(Vec3(reach.lo[0], reach.lo[1], reach.lo[2]));
    const CellCoord h = sums.grid.cellOf(Vec3(reach.hi[0], reach.hi[1], reach.hi[2]));
    const int32_t boxLo[3] = {l.x, l.y, l.z}, boxHi[3] = {h.x, h.y, h.z};
    boxRows = kPhotonCost * float(sums.cellCounts.count(boxLo, boxHi)) <= reach.ownCost;
    if (boxRows)
      for (int32_t z = l.z; z <= h.z; ++z)
        for (int32_t y = l.y; y <= h.y; ++y) {
          const CellPhotons row = sums.rowPhotons(l.x, h.x, y, z);
          if (row.count > 0) s.rows.push_back({row.first, row.count});
        }
  }

  for (size_t j = 0; j < cell.size(); ++j) {
    const CellQuery& q = cell[j];
    const QueryPlan& plan = s.plans[j];
    if (plan.how == QueryPlan::Done) continue;
    if (plan.how == QueryPlan::Search) {
      out[q.point] = estimateRadiance(map, estimatePoint(points[q.point]), settings, s.heap.data(), c);
      continue;
    }
    const GrowingRadius& radius = plan.radius;
    if (!boxRows) sphereRows(sums, q.position, radius.d2, s.ownRows);
    const std::span<const ColumnRun> rows = boxRows ? std::span<const ColumnRun>(s.rows) : s.ownRows;
    const SphereSum sphere = sumWithinRadius(sums.columns, rows, q.position, q.side, radius.d2);
    // The photon that set the radius is left out (see Accumulator::radiance).
    out[q.point] = radius.d2 > 0 ? diffuseRadiance(sphere.sum - radius.share, q.kd, radius.d2) : Rgb();
    ++c.queries;
    c.photonsUsed += sphere.used;
    c.photonsExamined += radius.examined;
    for (const ColumnRun& row : rows) c.photonsExamined += row.count;
    c.cellsVisited += uint32_t(rows.size());
  }
}

}  // namespace cell_estimate_detail

// The estimate of `map` (nullptr: none, black) at every point, into out[i]; per thread counters.
// `done` is told how many points each finished piece of work held (for progress).
template <class Map>
void estimateAtPoints(const Map* map, std::span<const ShadingPoint> points, const EstimateSettings& settings,
                      std::span<Rgb> out, tbb::enumerable_thread_specific<EstimateCounters>& counters,
                      const std::function<void(size_t)>& done = {}) {
  using namespace cell_estimate_detail;
  const size_t n = points.size();
  if (!map) {
    std::fill(out.begin(), out.end(), Rgb());
    if (done) done(n);
    return;
  }
  tbb::enumerable_thread_specific<Scratch> scratch([&] {
    Scratch s;
    s.heap.resize(settings.k);
    return s;
  });

  // By cell only where a whole search is wanted of a map with rows of cells as runs.
  bool byCell = settings.shells == 0;
  if constexpr (!(knn_grid_detail::kReadsRuns<Map> && knn_grid_detail::kHasCellCounts<Map>)) byCell = false;
  if (!byCell) {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1024), [&](const tbb::blocked_range<size_t>& r) {
      stopPoint();
      flushDenormals();
      Scratch& s = scratch.local();
      EstimateCounters& c = counters.local();
      for (size_t i = r.begin(); i != r.end(); ++i)
        out[i] = estimateRadiance(*map, estimatePoint(points[i]), settings, s.heap.data(), c);
      if (done) done(r.size());
    });
    return;
  }
  if constexpr (knn_grid_detail::kReadsRuns<Map> && knn_grid_detail::kHasCellCounts<Map>) {
    const UniformGrid& g = map->grid;
    const uint32_t k = settings.k;
    // The points by cell (then by index: the same groups whatever the thread count), and what the
    // estimate reads of them in that order.
    std::vector<uint32_t> order, groupStart;
    pointsByCell(g, points, order, groupStart);
    UninitializedVector<CellQuery> queries(n);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, kItemsPerTask), [&](const tbb::blocked_range<size_t>& r) {
      stopPoint();
      for (size_t j = r.begin(); j != r.end(); ++j) {
        const ShadingPoint& p = points[order[j]];
        queries[j] = {p.position, estimatePoint(p).side(), p.bsdf.diffuse(), order[j], p.bsdf.onlyDiffuse()};
      }
    });

    tbb::parallel_for(tbb::blocked_range<size_t>(0, groupStart.size() - 1, 16), [&](const tbb::blocked_range<size_t>& r) {
      stopPoint();
      flushDenormals();
      Scratch& s = scratch.local();
      EstimateCounters& c = counters.local();
      size_t pointsDone = 0;
      for (size_t group = r.begin(); group != r.end(); ++group) {
        const std::span<const CellQuery> cell(queries.data() + groupStart[group], groupStart[group + 1] - groupStart[group]);
        pointsDone += cell.size();
        const CellCoord cellCoord = g.cellOf(cell[0].position);
        s.order.begin(*map, cellCoord, k, settings.maxRadius);
        s.plans.resize(cell.size());
        const bool anyDiffuse = std::any_of(cell.begin(), cell.end(), [](const CellQuery& q) { return q.diffuse != 0; });
        if (anyDiffuse && s.order.recorded < k && !s.order.covers) s.order.extend(*map, k, settings.maxRadius);
        const CellReach reach = planCellQueries(*map, cell, settings, s, c, out);
        sumCellQueries(*map, cell, points, settings, reach, s, c, out);
      }
      if (done) done(pointsDone);
    });
  }
}

}  // namespace lucent
