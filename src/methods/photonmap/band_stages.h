// What purcell and pmfg do alike for each band of image rows: the shading points and their direct
// light, the band's dumps, and the totals both report the same way (the paper's Table 1 stages).
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <utility>

#include "lucent/core/stats.h"
#include "lucent/methods/photonmap.h"
#include "lucent/pipeline/film.h"
#include "lucent/pipeline/render_driver.h"
#include "lucent/pipeline/shading_points.h"
#include "lucent/techniques/photons/kd_tree.h"
#include "lucent/techniques/photons/photon_estimate.h"

namespace lucent {

// The first stage of both renderers for one band of rows: eye rays through mirrors and glass to
// their shading points, and the direct light at those points by shadow rays.
// A map's kNN search at every shading point, for dumps: point i's photons (indices into the map's
// photons) with their squared distances at [offsets[i], offsets[i + 1]).
struct NeighbourLists {
  std::vector<uint64_t> offsets;
  std::vector<PhotonDistance> entries;
};
struct BandShadingPoints {
  EyePaths eye;
  PointRadiance radiance;
  NeighbourLists neighbours[2];  // purcell's global and caustic searches, with a dump only
};
BandShadingPoints traceBand(const Scene& scene, const Visibility& vis, const PhotonMapOptions& options,
                            const PixelRect& band, const RenderPart& part, uint64_t& shadowRays);

void addEstimateCounters(RenderStats& stats, const std::string& prefix, const EstimateCounters& counters);

// Dumps (docs/dump-format.md) a band's shading points and the radiance each part of the estimate
// gives them as "band<N>.<array>" into options.dumpDirectory, when it is set.
// With the neighbour lists there are, as "band<N>.<map>.neighbours" and ".neighbour_offsets".
void dumpBand(const PhotonMapOptions& options, size_t band, const BandShadingPoints& traced);

// The band loop of both renderers (RenderDriver::renderBands): the part's rows in bands of at most
// options.bandSamples camera samples and about two seconds of work unless stages are dumped, from
// the first row the film does not hold in full (a resumed render). Each band is traced by
// traceBand, finished by `estimate` (the method's radiance estimates at its points; its progress
// callback takes the fraction of the band done), dumped, and added to the film. Between bands:
// checkpoints, and stop requests, after which it returns false.
struct RenderTotals;
bool renderBands(const Scene& scene, const Visibility& vis, const PhotonMapOptions& options, RenderDriver& driver,
                 RenderTotals& totals,
                 const std::function<void(BandShadingPoints& band, const std::function<void(double)>& progress)>& estimate);

// What both renderers add up over the bands, and report the same way: the paper's Table 1 stages
// trace_rays and radiance_estimate, and the ray, point and estimate counters.
struct RenderTotals {
  double traceSeconds = 0, estimateSeconds = 0;
  uint64_t eyeRays = 0, shadowRays = 0, points = 0, invalid = 0;  // invalid: camera paths and shading points dropped
  void addBand(const EyePaths& eye) {
    eyeRays += eye.rays;
    points += eye.points.size();
    invalid += eye.invalid;
  }
  void report(RenderStats& stats, const EstimateCounters& global, const EstimateCounters& caustic) const;
};

}  // namespace lucent
