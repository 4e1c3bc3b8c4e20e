// The ray-tracing stages shared by the photon-mapping renderers (Purcell et al. 2003, section 2.4:
// "a stochastic ray tracer ... recursive ray tracing for specular reflection and refraction and
// distributed tracing of shadow rays"): camera rays followed through mirrors and glass to the
// diffuse or glossy surfaces they reach, and direct light there by shadow rays.
#pragma once
#include <cstdint>
#include <span>
#include <type_traits>
#include <vector>

#include "lucent/core/rng.h"
#include "lucent/core/uninitialized.h"
#include "lucent/scene/bsdf.h"
#include "lucent/scene/scene.h"
#include "lucent/trace/visibility.h"
#include "radiance_estimate.h"

namespace lucent {

// Random-number streams of the renderers, so that no two stages share numbers.
enum class RenderStream : uint64_t { Eye = 1, Direct = 2, Gather = 3, CausticPhotons = 4 };
inline uint64_t streamSeed(uint64_t seed, RenderStream stream) { return hashKey(seed, uint64_t(stream)); }

// A diffuse or glossy surface point that a camera path reached, possibly through specular bounces.
struct ShadingPoint {
  Vec3 position;
  Vec3 geometricNormal;  // counter-clockwise winding normal (for ray offsets)
  Vec3 normal;           // shading normal, on the viewer's side
  Vec3 wo;               // towards the viewer
  Rgb weight;            // camera path throughput up to here
  SurfaceBsdf bsdf;      // Diffuse or Phong, non-black
  uint32_t pixel = 0;
  uint32_t sample = 0;   // the camera sample
  uint32_t branch = 0;   // index of this point among its camera sample's (specular splitting)
};
static_assert(sizeof(ShadingPoint) == 108 && std::is_trivially_copyable_v<ShadingPoint>, "dumped as records");

inline EstimatePoint estimatePoint(const ShadingPoint& sp) {
  EstimatePoint q;
  q.position = sp.position;
  q.frame = Frame(sp.normal);
  q.woLocal = q.frame.toLocal(sp.wo);
  q.bsdf = sp.bsdf;
  q.facingNormal = dot(sp.wo, sp.geometricNormal) > 0 ? sp.geometricNormal : -sp.geometricNormal;
  return q;
}

struct EyePathSettings {
  int spp = 1;
  int maxSpecularDepth = 10;
  uint64_t seed = 0;
  bool layers = false;
  int rowBegin = 0, rowEnd = 0;  // the band of image rows traced; rowEnd 0: to the last row
  int tileSize = 16;
};

// Per pixel, summed over its camera samples.
struct EyePixel {
  Rgb emitted;   // emission seen directly or through mirrors and glass (and the environment)
  Rgb albedo;    // first hit: reflectance (1 for glass); layers only
  Vec3 normal;   // first hit's shading normal; layers only
  float depth = 0;
  uint32_t validSamples = 0;  // camera samples kept (those with non-finite values are dropped)
};

// The arrays are written by the tiles in parallel (UninitializedVector).
struct EyePaths {
  UninitializedVector<ShadingPoint> points;  // by tile, then pixel, then sample, then branch
  UninitializedVector<EyePixel> pixels;      // the band's, from pixel firstPixel on (row rowBegin)
  uint32_t firstPixel = 0;
  uint64_t rays = 0;
  uint64_t invalid = 0;  // camera paths dropped for non-finite values
};

// Stage "trace_rays" (eye rays): a camera ray per sample (spp 1: through the pixel centre;
// otherwise stratified over the pixel), followed through mirrors (tinted by Ks) and glass up to
// maxSpecularDepth specular bounces. At glass both the reflected and the refracted ray are traced,
// weighted by Fresnel (deterministic splitting), while the branch's weight is at least
// kSplitWeight; a lighter branch continues along one of the two, chosen with the Fresnel
// probability (unbiased, and the number of branches stays small inside a glass ball).
inline constexpr float kSplitWeight = 0.05f;
EyePaths traceEyePaths(const Scene& scene, const Visibility& visibility, const EyePathSettings& settings);

// Stage "trace_rays" (shadow rays): direct light reflected towards the viewer at every point, by
// `samples` light samples (stratified over the light's area, lights chosen by power), each tested
// by one shadow ray; emitters, point, directional and environment lights alike. Adds the shadow
// rays traced to `rays`.
void estimateDirectLight(const Scene& scene, const Visibility& visibility, std::span<const ShadingPoint> points,
                         int samples, uint64_t seed, std::span<Rgb> direct, uint64_t& rays);

// One point's direct light, its shadow rays in packets of its own samples (estimateDirectLight
// packs rays across points instead).
Rgb directLight(const Scene& scene, const Visibility& visibility, const ShadingPoint& point, int samples,
                uint64_t seed, uint64_t& rays);

}  // namespace lucent
