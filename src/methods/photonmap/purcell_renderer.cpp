// --method purcell: the renderer of Purcell et al. 2003, sections 2.4 and 3, as data-parallel stages
// over the whole image (the paper's breadth-first passes): trace photons, build the maps, trace
// eye rays through mirrors and glass, shadow rays for direct light, then the radiance estimates of
// the global and caustic maps at every diffuse hit, visualized directly.
#include <tbb/enumerable_thread_specific.h>

#include <atomic>
#include <type_traits>

#include "lucent/core/parallel.h"
#include "estimate_by_cell.h"
#include "knn_grid.h"
#include "band_stages.h"
#include "photon_maps.h"

namespace lucent {

namespace {

// What the kNN search finds at every point, for the dump: the whole search (a map's `shells`
// setting is ignored), the photons it accepts with their squared distances. Grid maps accept every
// photon within the final radius (knn_grid.h), the kd-tree the k nearest.
template <class Map>
NeighbourLists searchNeighbours(const Map* map, std::span<const ShadingPoint> points, const EstimateSettings& settings) {
  NeighbourLists lists;
  if (!map) return lists;
  std::vector<std::vector<PhotonDistance>> found(points.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, points.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
    std::vector<PhotonDistance> heap(settings.k);
    for (size_t i = r.begin(); i != r.end(); ++i) {
      if constexpr (std::is_same_v<Map, PhotonKdTree>) {
        const KdTreeResult result = kdTreeNearest(*map, points[i].position, settings.k, settings.maxRadius, heap.data());
        found[i].assign(heap.begin(), heap.begin() + result.found);
      } else {
        knnGrid(*map, points[i].position, settings.k, settings.maxRadius,
                [&](uint32_t id, const Photon&, float d2) { found[i].push_back({d2, id}); });
      }
    }
  });
  lists.offsets.push_back(0);
  for (const std::vector<PhotonDistance>& f : found) {
    lists.entries.insert(lists.entries.end(), f.begin(), f.end());
    lists.offsets.push_back(lists.entries.size());
  }
  return lists;
}

}  // namespace

RenderOutput renderPurcell(const Scene& scene, const Visibility& vis, const PhotonMapOptions& options,
                           const RenderControl& control) {
  RenderDriver driver(purcellOptionTable(), options, control, scene, vis);
  if (options.bandSamples < 1) throw std::invalid_argument("band samples must be at least 1");
  RenderOutput out;
  // The global map without direct and caustic photons: direct light comes from shadow rays and
  // caustics from the caustic map, so each light path is counted once.
  const RenderPhotonMaps maps = preparePhotonMaps(scene, vis, options, GlobalPhotons::Indirect, out.stats);

  const Film& film = driver.startFilm(Film::Sums::PerPart, {options.common.layers, true});
  tbb::enumerable_thread_specific<EstimateCounters> globalCounters, causticCounters;
  RenderTotals totals;
  renderBands(scene, vis, options, driver, totals, [&](BandShadingPoints& band, const auto& progress) {
    // The radiance estimate at every shading point, from both maps.
    Stopwatch estimateClock;
    const size_t n = band.eye.points.size();
    std::atomic<size_t> done{0};
    auto reportDone = [&](size_t count) { progress(0.5 * double(done += count) / double(n)); };
    withPhotonMaps(maps, options.map, [&](const auto* global, const auto* caustic) {
      estimateAtPoints(global, band.eye.points, maps.globalSettings, band.radiance.indirect, globalCounters, reportDone);
      estimateAtPoints(caustic, band.eye.points, maps.causticSettings, band.radiance.caustic, causticCounters, reportDone);
    });
    totals.estimateSeconds += estimateClock.seconds();
    if (!options.shading.dumpDirectory.empty())  // not timed: a dump's own work
      withPhotonMaps(maps, options.map, [&](const auto* global, const auto* caustic) {
        band.neighbours[0] = searchNeighbours(global, band.eye.points, maps.globalSettings);
        band.neighbours[1] = searchNeighbours(caustic, band.eye.points, maps.causticSettings);
      });
  });

  driver.finish(out);
  totals.invalid += film.droppedPoints();
  EstimateCounters gc, cc;
  for (const auto& c : globalCounters) gc += c;
  for (const auto& c : causticCounters) cc += c;
  totals.report(out.stats, gc, cc);
  return out;
}

}  // namespace lucent
