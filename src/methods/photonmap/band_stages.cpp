#include "methods/photonmap/band_stages.h"

#include "lucent/core/dump.h"
#include "lucent/pipeline/direct_light.h"
#include "lucent/pipeline/dumps.h"

namespace lucent {

void dumpBand(const PhotonMapOptions& options, size_t band, const BandShadingPoints& traced) {
  const std::string& dir = options.shading.dumpDirectory;
  if (dir.empty()) return;
  const std::string prefix = "band" + std::to_string(band) + ".";
  dumpShadingPoints(dir, prefix, traced.eye, traced.radiance, true);
  const char* maps[2] = {"global", "caustic"};
  for (int m = 0; m < 2; ++m) {
    const NeighbourLists& n = traced.neighbours[m];
    if (n.offsets.empty()) continue;
    writeDump(dir, prefix + maps[m] + ".neighbour_offsets", "uint64", std::span(n.offsets));
    writeDump(dir, prefix + maps[m] + ".neighbours", "PhotonDistance", std::span(n.entries));
  }
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
  EyePathSettings eyeSettings = eyePathSettings(options.common, options.shading.maxSpecularDepth, part);
  eyeSettings.region = band;
  BandShadingPoints out{traceEyePaths(scene, vis, eyeSettings), PointRadiance(0), {}};
  out.radiance = PointRadiance(out.eye.points.size());
  if (options.shading.lightSamples > 0)
    estimateDirectLight(scene, vis, out.eye.points, options.shading.lightSamples, options.common.seed, out.radiance.direct, shadowRays);
  return out;
}

bool renderBands(const Scene& scene, const Visibility& vis, const PhotonMapOptions& options, RenderDriver& driver,
                 RenderTotals& totals,
                 const std::function<void(BandShadingPoints& band, const std::function<void(double)>& progress)>& estimate) {
  const RenderPart& part = driver.part();
  // Dumped bands are named by their index: fixed bands, whatever the time they take.
  BandLoop loop;
  loop.maxSamples = options.bandSamples;
  loop.targetSeconds = options.shading.dumpDirectory.empty() ? 2.0 : 0.0;
  beginStage("bands");
  return driver.renderBands(loop, [&](const PixelRect& band, size_t index, const auto& progress) {
    Stopwatch rayClock;
    uint64_t bandShadowRays = 0;  // counted once the band is kept
    BandShadingPoints traced = traceBand(scene, vis, options, band, part, bandShadowRays);
    totals.traceSeconds += rayClock.seconds();
    estimate(traced, progress);
    dumpBand(options, index, traced);
    addBand(driver.film(), traced.eye, traced.radiance, scene.camera.width, part);
    totals.shadowRays += bandShadowRays;
    totals.addBand(traced.eye);
  });
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
