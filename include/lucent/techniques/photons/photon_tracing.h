// Breadth-first photon tracing (Purcell et al. 2003, section 2.1): all photons advance one bounce per
// stage, as a wavefront, so that every stage is one data-parallel pass over flat arrays.
#pragma once
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "lucent/core/stats.h"
#include "lucent/scene/light_sampling.h"
#include "lucent/scene/scene.h"
#include "lucent/techniques/photons/photon.h"
#include "lucent/trace/visibility.h"

namespace lucent {

struct PhotonTracingOptions {
  uint32_t photons = 65000;  // photon paths emitted
  uint32_t maxBounces = 64;  // interactions followed per path (Russian roulette ends most far earlier)
  uint64_t seed = 0;
  // Trace for the caustic map alone: a path ends at its first non-specular surface (after storing
  // there when it came through specular bounces), and `global` stays empty.
  bool causticOnly = false;
  // Emit only towards this sphere (see EmissionTarget); with causticOnly, the specular objects'.
  std::optional<EmissionTarget> target;
  // The option that sets `photons`, named when they would not fit in memory (requireMemory).
  std::string photonsOption = "--photons";
};

// The bounding sphere of the scene's triangles that may be passed as specular (mirrors, glass and
// smooth transmitters: mayPassAsSpecular), where caustic paths must start, with a projection map
// of them for each point light outside it; none when the scene has no such surface.
std::optional<EmissionTarget> specularTarget(const Scene& scene);

// Photons stored at surfaces not passed as specular (SurfaceBsdf::passedAsSpecular). The caustic
// map holds those that reached one through surfaces passed as specular only (L S+ D: mirrors,
// glass, smooth transmitters, whichever part of their lobe scattered); the global map holds every stored photon
// (L {S|D}* D), direct ones included. Caustic photons carry kPhotonCausticFlag in both maps.
struct PhotonMaps {
  std::vector<Photon> global;
  std::vector<Photon> caustic;
  uint32_t emitted = 0;
  std::vector<uint32_t> alivePerBounce;  // photons entering each stage
  RenderStats stats;
};

PhotonMaps tracePhotons(const Scene& scene, const Visibility& visibility, const PhotonTracingOptions& options);

}  // namespace lucent
