// --method purcell: the renderer of Purcell et al. 2003, sections 2.4 and 3, as data-parallel stages
// over the whole image (the paper's breadth-first passes): trace photons, build the maps, trace
// eye rays through mirrors and glass, shadow rays for direct light, then the radiance estimates of
// the global and caustic maps at every diffuse hit, visualized directly.
#include <tbb/enumerable_thread_specific.h>

#include <atomic>

#include "lucent/core/parallel.h"
#include "estimate_by_cell.h"
#include "band_stages.h"
#include "photon_maps.h"

namespace lucent {

RenderOutput renderPurcell(const Scene& scene, const Visibility& vis, const PhotonMapOptions& options,
                           const RenderControl& control) {
  const RenderPart part = beginRender(purcellOptionTable(), options, control, scene);
  if (options.bandSamples < 1) throw std::invalid_argument("band samples must be at least 1");
  RenderOutput out;
  // The global map without direct and caustic photons: direct light comes from shadow rays and
  // caustics from the caustic map, so each light path is counted once.
  const RenderPhotonMaps maps = preparePhotonMaps(scene, vis, options, GlobalPhotons::Indirect, out.stats);

  auto film = std::make_shared<Film>(startFilm(control, scene, part, Film::Sums::PerPart, {options.common.layers, true}));
  tbb::enumerable_thread_specific<EstimateCounters> globalCounters, causticCounters;
  RenderTotals totals;
  renderBands(scene, vis, options, control, part, *film, totals, [&](BandShadingPoints& band, const auto& progress) {
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
  });

  out.complete = filmComplete(*film, part);
  out.sppDone = out.complete ? part.samples() : 0;
  out.image = film->image();
  out.film = film;
  totals.invalid += film->droppedPoints();
  EstimateCounters gc, cc;
  for (const auto& c : globalCounters) gc += c;
  for (const auto& c : causticCounters) cc += c;
  totals.report(out.stats, gc, cc);
  return out;
}

}  // namespace lucent
