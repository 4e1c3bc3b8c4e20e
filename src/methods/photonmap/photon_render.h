// What the two photon-mapping renderers share: their photon maps (traced, selected and built into
// the chosen structure), the dispatch to one instantiation per map type, and the image assembly.
#pragma once
#include <span>
#include <variant>

#include "lucent/methods/photons/kd_tree.h"
#include "methods/photonmap/photon_mapping.h"
#include "lucent/pipeline/direct_light.h"
#include "lucent/pipeline/dumps.h"
#include "lucent/pipeline/film.h"
#include "lucent/pipeline/shading_points.h"
#include "radiance_estimate.h"
#include "sorted_grid.h"
#include "stencil_grid.h"

namespace lucent {

// One photon map in the structure chosen; monostate when it holds no photons.
struct BuiltPhotonMap {
  std::variant<std::monostate, SortedGrid, StencilGrid, HashedGrid, PhotonKdTree> map;
  size_t photons = 0;
};

// Which photons of the global map a renderer reads.
enum class GlobalPhotons {
  All,       // every stored photon, direct ones included (final gathering: pmfg)
  Indirect,  // photons after at least one bounce that are not caustic photons (purcell: direct
             // light comes from shadow rays and caustics from the caustic map)
};

struct RenderPhotonMaps {
  BuiltPhotonMap global, caustic;
  EstimateSettings globalSettings, causticSettings;
};

// The grid of a map searched for k photons, as the render options ask for it.
GridOptions gridOptionsFor(const PhotonMapOptions& options, uint32_t k);

// The global and caustic maps' estimate settings, as the render options ask for them (the caustic
// k defaults to k; the maximum radius to defaultMaxRadius).
struct MapEstimateSettings {
  EstimateSettings global, caustic;
};
MapEstimateSettings estimateSettingsFor(const Scene& scene, const PhotonMapOptions& options);

// Stages "trace_photons" (the global pass, and a caustic-only pass of causticPhotons paths) and
// "build_map" (both maps), timed into `stats` with their sub-stages and counters.
RenderPhotonMaps preparePhotonMaps(const Scene& scene, const Visibility& visibility, const PhotonMapOptions& options,
                                   GlobalPhotons which, RenderStats& stats);

// Calls f(global, caustic) with typed pointers to the maps (nullptr for an empty one), so that the
// stages that search them are compiled once per map type.
template <class F>
void withPhotonMaps(const RenderPhotonMaps& maps, PhotonMapKind kind, F&& f) {
  auto call = [&](auto* type) {
    using Map = std::remove_pointer_t<decltype(type)>;
    f(std::get_if<Map>(&maps.global.map), std::get_if<Map>(&maps.caustic.map));
  };
  switch (kind) {
    case PhotonMapKind::Sort: call(static_cast<SortedGrid*>(nullptr)); break;
    case PhotonMapKind::Stencil: call(static_cast<StencilGrid*>(nullptr)); break;
    case PhotonMapKind::Hash: call(static_cast<HashedGrid*>(nullptr)); break;
    case PhotonMapKind::KdTree: call(static_cast<PhotonKdTree*>(nullptr)); break;
  }
}

// The first stage of both renderers for one band of rows: eye rays through mirrors and glass to
// their shading points, and the direct light at those points by shadow rays.
struct BandShadingPoints {
  EyePaths eye;
  PointRadiance radiance;
};
BandShadingPoints traceBand(const Scene& scene, const Visibility& vis, const PhotonMapOptions& options,
                            std::pair<int, int> band, uint64_t& shadowRays);

void addEstimateCounters(RenderStats& stats, const std::string& prefix, const EstimateCounters& counters);

// Dumps (docs/dump-format.md) into options.dumpDirectory, when it is set: a map's arrays as
// "<prefix>.<array>" (prefix "global" or "caustic"), and a band's shading points and the radiance
// each part of the estimate gives them as "band<N>.<array>".
void dumpPhotonMap(const PhotonMapOptions& options, const std::string& prefix, const BuiltPhotonMap& map);
void dumpBand(const PhotonMapOptions& options, size_t band, const EyePaths& eye, const PointRadiance& radiance);

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
