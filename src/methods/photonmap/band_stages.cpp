#include "methods/photonmap/band_stages.h"

#include <optional>

#include "lucent/core/stop.h"
#include "lucent/pipeline/direct_light.h"
#include "lucent/pipeline/dumps.h"

namespace lucent {

void dumpBand(const PhotonMapOptions& options, size_t band, const EyePaths& eye, const PointRadiance& radiance) {
  if (options.dumpDirectory.empty()) return;
  dumpShadingPoints(options.dumpDirectory, "band" + std::to_string(band) + ".", eye, radiance, true);
}

void addEstimateCounters(RenderStats& stats, const std::string& prefix, const EstimateCounters& c) {
  stats.addCounter(prefix + "_estimates", c.queries);
  stats.addCounter(prefix + "_photons_used", c.photonsUsed);
  stats.addCounter(prefix + "_photons_examined", c.photonsExamined);
  if (c.cellsVisited > 0) stats.addCounter(prefix + "_cells_visited", c.cellsVisited);
  if (c.unfinished > 0) stats.addCounter(prefix + "_searches_unfinished", c.unfinished);
}

BandShadingPoints traceBand(const Scene& scene, const Visibility& vis, const PhotonMapOptions& options,
                            const PixelRect& band, const RenderPart& part, uint64_t& shadowRays) {
  EyePathSettings eyeSettings = eyePathSettings(options, part);
  eyeSettings.region = band;
  BandShadingPoints out{traceEyePaths(scene, vis, eyeSettings), PointRadiance(0)};
  out.radiance = PointRadiance(out.eye.points.size());
  if (options.lightSamples > 0)
    estimateDirectLight(scene, vis, out.eye.points, options.lightSamples, options.seed, out.radiance.direct, shadowRays);
  return out;
}

bool renderBands(const Scene& scene, const Visibility& vis, const PhotonMapOptions& options,
                 const RenderControl& control, const RenderPart& part, Film& film, RenderTotals& totals,
                 const std::function<void(BandShadingPoints& band, const std::function<void(double)>& progress)>& estimate) {
  const PixelRect& region = part.region;
  const int width = scene.camera.width;
  auto rowDone = [&](int y) {
    for (int x = region.x0; x < region.x1; ++x)
      if (film.taken(uint64_t(y) * uint64_t(width) + uint64_t(x)) != uint32_t(part.samples())) return false;
    return true;
  };
  int row = region.y0;
  while (row < region.y1 && rowDone(row)) ++row;
  // Dumped bands are named by their index: fixed bands, whatever the time they take.
  RowBands bands(part, options.bandSamples, options.dumpDirectory.empty() ? 2.0 : 0.0);
  CheckpointClock checkpoints(control);
  const double rows = region.height();
  beginStage("bands");
  for (size_t index = 0; row < region.y1; ++index) {
    if (control.stopRequested()) return false;
    Stopwatch bandClock;
    // Not a structured binding: the lambda below captures them (Clang 14 cannot).
    const std::pair<int, int> next = bands.next(row);
    const int first = next.first, end = next.second;
    const PixelRect band{region.x0, first, region.x1, end};
    Stopwatch rayClock;
    // A stop in the middle of a band drops the band: the film keeps the bands before it whole.
    std::optional<BandShadingPoints> traced;
    uint64_t bandShadowRays = 0;  // counted once the band is kept
    try {
      traced.emplace(traceBand(scene, vis, options, band, part, bandShadowRays));
      totals.traceSeconds += rayClock.seconds();
      estimate(*traced, [&](double fraction) {
        if (control.progress) control.progress((double(first - region.y0) + fraction * (end - first)) / rows);
      });
    } catch (const RenderStopped&) {
      return false;
    }
    dumpBand(options, index, traced->eye, traced->radiance);
    addBand(film, traced->eye, traced->radiance, width, part);
    totals.shadowRays += bandShadowRays;
    totals.addBand(traced->eye);
    bands.finished(end - first, bandClock.seconds());
    row = end;
    if (row < region.y1) checkpoints.reached(film);
  }
  return true;
}

void RenderTotals::report(RenderStats& stats, const EstimateCounters& global, const EstimateCounters& caustic) const {
  stats.addStage("trace_rays", traceSeconds);
  stats.addStage("radiance_estimate", estimateSeconds);
  stats.addCounter("eye_rays", eyeRays);
  stats.addCounter("shadow_rays", shadowRays);
  stats.addCounter("shading_points", points);
  stats.addCounter("invalid_samples", invalid);
  addEstimateCounters(stats, "global", global);
  addEstimateCounters(stats, "caustic", caustic);
}

}  // namespace lucent
