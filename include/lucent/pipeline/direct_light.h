// Direct light at shading points by shadow rays (Purcell et al. 2003, 2.4: "distributed tracing of
// shadow rays"): the light reflected towards the viewer from emitters, point, directional and
// environment lights, each sample tested by one Embree shadow ray.
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "lucent/core/distribution.h"

#include "lucent/pipeline/shading_points.h"

namespace lucent {

// The scene's lights as the direct-light estimates take them: one shadow ray to each point and
// directional light (exact but for its visibility), light samples among the others, chosen by their
// estimated power, each owning a cell of the choice's grid however dim (Distribution1D).
struct DirectLights {
  explicit DirectLights(const Scene& scene);
  std::vector<uint32_t> delta;    // the point, spot and directional lights
  bool anySampled = false;        // whether there are other lights
  std::vector<uint32_t> sampled;  // the others
  Distribution1D choice;          // over `sampled`
};

// Stage "trace_rays" (shadow rays): direct light reflected towards the viewer at every point: one
// shadow ray to each point and directional light, and `samples` samples of the other lights
// (stratified over the light's area), each tested by one shadow ray; samples 0: none at all (zero).
// Adds the shadow rays traced to `rays`.
void estimateDirectLight(const Scene& scene, const Visibility& visibility, std::span<const ShadingPoint> points,
                         int samples, uint64_t seed, std::span<Rgb> direct, uint64_t& rays);

// The direct light of the scene's point and directional lights at every point, one shadow ray to
// each (no sampling: exact but for its visibility), in packets across points. The other lights
// are left out (for methods that take them another way). Adds the rays traced to `rays`.
void analyticDirectLight(const Scene& scene, const Visibility& visibility, std::span<const ShadingPoint> points,
                         std::span<Rgb> direct, uint64_t& rays);

// One point's direct light as estimateDirectLight's, its shadow rays in packets of its own samples
// (estimateDirectLight packs rays across points instead); with `samples` 0, that of the point,
// spot and directional lights alone (for a point whose other light rays bring, no ray meeting
// those).
Rgb directLight(const Scene& scene, const DirectLights& lights, const Visibility& visibility, const ShadingPoint& point,
                int samples, uint64_t seed, uint64_t& rays);

}  // namespace lucent
