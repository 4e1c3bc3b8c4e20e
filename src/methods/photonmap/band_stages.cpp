#include "methods/photonmap/band_stages.h"

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
                            std::pair<int, int> band, uint64_t& shadowRays) {
  EyePathSettings eyeSettings{options.spp, options.maxSpecularDepth, options.seed, options.layers};
  eyeSettings.rowBegin = band.first;
  eyeSettings.rowEnd = band.second;
  BandShadingPoints out{traceEyePaths(scene, vis, eyeSettings), PointRadiance(0)};
  out.radiance = PointRadiance(out.eye.points.size());
  if (options.lightSamples > 0)
    estimateDirectLight(scene, vis, out.eye.points, options.lightSamples, options.seed, out.radiance.direct, shadowRays);
  return out;
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
