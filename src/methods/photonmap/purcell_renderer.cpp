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
                           const ProgressFn& progress) {
  purcellOptionTable().validate(options);
  if (options.bandSamples < 1) throw std::invalid_argument("band samples must be at least 1");
  RenderOutput out;
  // The global map without direct and caustic photons: direct light comes from shadow rays and
  // caustics from the caustic map, so each light path is counted once.
  const RenderPhotonMaps maps = preparePhotonMaps(scene, vis, options, GlobalPhotons::Indirect, out.stats);

  Film film(scene.camera.width, scene.camera.height, Film::Sums::PerPart, {options.layers, true});
  tbb::enumerable_thread_specific<EstimateCounters> globalCounters, causticCounters;
  RenderTotals totals;
  const auto bands = imageBands(scene, options.spp, options.bandSamples);
  for (size_t band = 0; band < bands.size(); ++band) {
    // Eye rays and shadow rays.
    Stopwatch rayClock;
    BandShadingPoints traced = traceBand(scene, vis, options, bands[band], totals.shadowRays);
    const EyePaths& eye = traced.eye;
    PointRadiance& radiance = traced.radiance;
    const size_t n = eye.points.size();
    totals.traceSeconds += rayClock.seconds();

    // The radiance estimate at every shading point, from both maps.
    Stopwatch estimateClock;
    std::atomic<size_t> done{0};
    auto reportDone = [&](size_t count) {
      if (progress) progress((double(band) + 0.5 * double(done += count) / double(n)) / double(bands.size()));
    };
    withPhotonMaps(maps, options.map, [&](const auto* global, const auto* caustic) {
      estimateAtPoints(global, eye.points, maps.globalSettings, radiance.indirect, globalCounters, reportDone);
      estimateAtPoints(caustic, eye.points, maps.causticSettings, radiance.caustic, causticCounters, reportDone);
    });
    totals.estimateSeconds += estimateClock.seconds();
    dumpBand(options, band, eye, radiance);
    film.add(eye, radiance);
    totals.addBand(eye);
  }

  out.image = film.image();
  out.sppDone = options.spp;
  totals.invalid += film.droppedPoints();
  EstimateCounters gc, cc;
  for (const auto& c : globalCounters) gc += c;
  for (const auto& c : causticCounters) cc += c;
  totals.report(out.stats, gc, cc);
  return out;
}

}  // namespace lucent
