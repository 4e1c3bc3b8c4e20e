// Direct light at the hierarchy's points under an environment (the environment-lighting PBGI paper,
// 3.2, 3.3, 4 "Calculate Direct Illumination", "Propagate Illumination"): micro-buffers rendered from
// surface points, integrated against the environment through their empty texels (Eq. 2 and 4), the
// directional and point lights by a shadow ray each, and propagation through the hierarchy.
#pragma once
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "lucent/scene/scene.h"
#include "lucent/techniques/microbuffers/hemisphere_mapping.h"
#include "lucent/techniques/microbuffers/micro_rendering.h"
#include "lucent/trace/visibility.h"
#include "methods/envpbgi/env_points.h"

namespace lucent {

// A micro-buffer's texels as a quadrature of the hemisphere: each used texel's direction (local
// frame, at the texel's centre) and its weight cos(theta) dOmega, the weights scaled so that they sum
// to pi (Eq. 2's sum is then exact for a constant radiance: notes A10).
struct BufferQuadrature {
  int side = 0;
  HemisphereMapping mapping;
  std::vector<float> cosineWeight;  // per texel, 0 for unused ones
  uint32_t texels() const { return uint32_t(side * side); }
};
BufferQuadrature makeQuadrature(MappingKind kind, int side);

// Where a micro-buffer is rendered from: a surface point and its normal (the frame is Frame(normal):
// the same for the same normal, so that results do not depend on anything else), and the
// geometric normal that cuts it (GatherPoint::surfaceNormal).
struct BufferOrigin {
  Vec3 position, normal, surfaceNormal;
};
// A surfel's buffer: its normal is its surface's, so nothing is cut.
inline BufferOrigin surfelOrigin(const Surfel& s) { return {s.position, s.normal, s.normal}; }

// Renders the micro-buffers of origins 0 .. count - 1 (origin(k)), in packets of kGatherPacket
// origins that face alike and lie near each other (sorted by facing, then Morton code), in
// parallel; buffer k's texels (packed depth | node words) go to texels[k * q.texels() ...]. Adds the
// traversal's counters to `counters`.
void renderBuffers(const MicroHierarchy& hierarchy, const MicroRenderSettings& settings, const BufferQuadrature& q,
                   size_t count, const std::function<BufferOrigin(size_t)>& origin, std::span<uint32_t> texels,
                   MicroCounters& counters);

// Eq. 2 and 4 over one buffer: the irradiance from its empty texels (the environment, Eq. 2's direct
// term) and from its full ones (the nodes' direct radiance, Eq. 4), apart. nodeDirect empty: the
// nodes' part is left 0.
struct BufferIrradiance {
  Rgb environment, nodes;
};
BufferIrradiance bufferIrradiance(std::span<const uint32_t> texels, const BufferQuadrature& q, Vec3 normal,
                                  const Environment& environment, std::span<const Rgb> nodeDirect);

// The irradiance of the directional and point lights at p (normal n), each by one shadow ray (the
// paper's shadow map). Adds the rays to `rays`.
Rgb analyticIrradiance(const Scene& scene, const Visibility& visibility, Vec3 p, Vec3 n, uint64_t& rays);

// The scene's lights are ones the method handles: the environment, directional and point lights,
// not emitting triangles; throws std::invalid_argument otherwise.
void requireEnvironmentLights(const Scene& scene);

// 3.4, 4 "Propagate Illumination": direct light copied from every primary point to the secondary
// points below it (downward), then averaged by area from the children of every covered node other
// than a primary point that is derivable or not a secondary point (upward, the arrival counters
// again). `direct` holds the
// primary points' and own-buffer points' light on entry; every secondary point has light after
// (kHasDirect).
void propagateDirectLight(EnvHierarchy& h, std::span<const uint32_t> primary, std::span<Rgb> direct);

}  // namespace lucent
