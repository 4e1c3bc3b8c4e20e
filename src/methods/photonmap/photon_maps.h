// The photon maps of the two photon-mapping renderers: traced, selected and built into the chosen
// structure, and the dispatch to one instantiation of a stage per map type.
#pragma once
#include <span>
#include <variant>

#include "lucent/methods/photonmap.h"
#include "lucent/techniques/photons/kd_tree.h"
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

// Dumps (docs/dump-format.md) a map's arrays as "<prefix>.<array>" (prefix "global" or "caustic")
// into options.dumpDirectory, when it is set.
void dumpPhotonMap(const PhotonMapOptions& options, const std::string& prefix, const BuiltPhotonMap& map);

}  // namespace lucent
