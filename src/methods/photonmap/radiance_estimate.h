// The radiance estimate on Purcell's grid maps (Purcell et al. 2003, 2.3): the kNN-grid's search
// (all photons within its final radius are summed, at least k of them) feeding the estimate of
// photon_estimate.h, where the point, the settings, the sums and the kd-tree's estimate are.
//
// One template per map (no virtual calls in the loop over photons); the renderers instantiate
// their stages once per map type.
#pragma once
#include <cstdint>

#include "knn_grid.h"
#include "lucent/techniques/photons/photon_estimate.h"
#include "photon_columns.h"

namespace lucent {

namespace estimate_detail {

// The kNN-grid's visitor: a Lambertian surface's runs of photons summed from the map's columns
// (photon_columns.h), other photons added one by one. Every run of a search goes the same way.
struct GridVisitor {
  Accumulator& acc;
  PhotonLaneSums lanes;

  void operator()(uint32_t, const Photon& p, float d2) { acc.add(p, d2); }
  bool takeRun(const CellPhotons& run, KnnGridSearch& s) {
    if (!acc.diffuse || !run.columns) return false;
    sumPhotonRun(*run.columns, run.first, run.first + run.count, acc.side, s, lanes);
    return true;
  }
  // Adds the lanes' sums to the accumulator at the end of the search; call it exactly once (the
  // lanes are not cleared).
  void finish() {
    const PhotonRunTotals t = photonRunTotals(lanes);
    acc.sum += t.sum;
    acc.used += t.used;
    if (t.farthestD2 > acc.farthestD2) acc.farthestD2 = t.farthestD2, acc.farthest = t.farthest;
  }
};

}  // namespace estimate_detail

// On a grid map: the kNN-grid search (knn_grid.h), whole or stopped after `shells` shells, in
// which case the running estimate over the radius reached so far is returned (section 3.4).
template <GridPhotonMap Map>
Rgb estimateRadiance(const Map& map, const EstimatePoint& q, const EstimateSettings& settings, PhotonDistance*,
                     EstimateCounters& counters) {
  estimate_detail::Accumulator acc(q);
  estimate_detail::GridVisitor visit{acc, {}};
  KnnGridSearch s = beginKnnGrid(q.position, settings.k, settings.maxRadius);
  advanceKnnGrid(map, s, settings.shells > 0 ? settings.shells : UINT32_MAX, visit);
  visit.finish();
  ++counters.queries;
  counters.photonsUsed += acc.used;
  counters.photonsExamined += s.photonsExamined;
  counters.cellsVisited += s.cellsVisited;
  counters.unfinished += !s.done;
  return acc.radiance(knnGridRadius2(s));
}

}  // namespace lucent
