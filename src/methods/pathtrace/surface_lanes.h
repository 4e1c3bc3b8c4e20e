// The wavefront path tracer's shading of Lambertian and glTF hits, many paths at a time: the scene
// data and random numbers of each hit are fetched into a structure of arrays (one slot per path, a "lane"),
// then every step that is the same arithmetic for all lanes runs as one loop over the lanes, which
// the compiler vectorizes (eight lanes per instruction with AVX2, sixteen with AVX-512, chosen at
// run time). The same loop over one lane shades single paths (PathTraceOptions::laneShading off);
// it calls the functions PathTracer::shade, which shades the other materials' hits, calls
// (shading_steps.h).
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "lucent/core/path_sampler.h"
#include "lucent/methods/pathtrace.h"
#include "lucent/scene/bsdf/gltf_metal_rough.h"
#include "lucent/scene/surface.h"
#include "lucent/scene/camera.h"
#include "lucent/scene/light_sampling.h"
#include "lucent/scene/texture.h"
#include "lucent/trace/visibility.h"

namespace lucent {

// Lanes per structure: the path tracer's wave (waves of 256 measured fastest once the arrays were
// padded: 128 1-2% slower, 512 no faster; docs/measurements/pathtrace.md).
inline constexpr int kMaxLanes = 256;
// Each lane array holds kMaxLanes entries and 16 unused ones (a cache line of floats): with arrays
// a power of two bytes long, the dozens of arrays a lane loop walks at once fell into few sets of
// the first-level cache (lane k of every array at the same address modulo 4 KiB) and evicted each
// other; waves of 512 paths ran 1.8x slower for it (1450 against 802 ms), 128 about 1%.
inline constexpr int kLaneSlots = kMaxLanes + 16;

// Lambertian hits fill the lanes from the first up ([0, count)), glTF hits from the last down
// ([gltfFirst, kMaxLanes)): a wave's hits are at most kMaxLanes, so the two never meet.
struct SurfaceLanes {
  uint32_t count = 0;
  uint32_t gltfFirst = kMaxLanes;
  PathStrategy strategy = PathStrategy::Mis;  // how light is found, the same for every lane
  // Fetched per lane (PathTracer::fetchLane). Normals: ng* the triangle's geometric one,
  // normal* the vertex normals interpolated (not yet normalized).
  alignas(64) float dirX[kLaneSlots], dirY[kLaneSlots], dirZ[kLaneSlots];  // the incoming ray
  alignas(64) float posX[kLaneSlots], posY[kLaneSlots], posZ[kLaneSlots];           // the hit point
  alignas(64) float normalX[kLaneSlots], normalY[kLaneSlots], normalZ[kLaneSlots];  // vertex normals interpolated
  alignas(64) int32_t hasNormals[kLaneSlots];
  alignas(64) float ngx[kLaneSlots], ngy[kLaneSlots], ngz[kLaneSlots];  // the triangle's geometric normal
  alignas(64) float kdR[kLaneSlots], kdG[kLaneSlots], kdB[kLaneSlots];  // textured albedo (glTF: base colour)
  alignas(64) int32_t emits[kLaneSlots];  // Ke not black: only then is gatherEmission called
  alignas(64) float uLightX[kLaneSlots], uLightY[kLaneSlots], uBsdfX[kLaneSlots], uBsdfY[kLaneSlots];
  alignas(64) float uRoulette[kLaneSlots];  // the next bounce's, drawn with the others (Sobol), or kDrawLater
  alignas(64) float uLobe[kLaneSlots];      // glTF: the choice between the GGX and the cosine lobe
  alignas(64) uint32_t path[kLaneSlots];  // the wave's path in this lane
  alignas(64) uint32_t light[kLaneSlots];  // the light sampled (for the pilot's light moments)

  // The light sample. Triangle lights (fetchLane): vertices q*, normal, area and pmf; the
  // lanes sample the point. Other lights (sampleOtherLights): the finished sample, wi* to lightDelta.
  alignas(64) int32_t lightIsTriangle[kLaneSlots];
  alignas(64) float q0x[kLaneSlots], q0y[kLaneSlots], q0z[kLaneSlots], q1x[kLaneSlots], q1y[kLaneSlots],
      q1z[kLaneSlots], q2x[kLaneSlots], q2y[kLaneSlots], q2z[kLaneSlots];
  alignas(64) float lightNx[kLaneSlots], lightNy[kLaneSlots], lightNz[kLaneSlots], lightArea[kLaneSlots],
      lightPmf[kLaneSlots];
  alignas(64) float wiX[kLaneSlots], wiY[kLaneSlots], wiZ[kLaneSlots], lightDistance[kLaneSlots];
  alignas(64) float pointX[kLaneSlots], pointY[kLaneSlots], pointZ[kLaneSlots];
  alignas(64) float leR[kLaneSlots], leG[kLaneSlots], leB[kLaneSlots], lightPdf[kLaneSlots];
  alignas(64) int32_t lightDelta[kLaneSlots];

  // glTF hits (fetchGltfSurface): the factors of metalRoughLobe, their textures applied; the
  // vertices' tangents interpolated and the normal texture's texel (linear), where the material has
  // one; the geometric normal's side of the frame (shadingFrameNormal's).
  alignas(64) float metallic[kLaneSlots], roughness[kLaneSlots];
  alignas(64) float f0R[kLaneSlots], f0G[kLaneSlots], f0B[kLaneSlots], specular[kLaneSlots];
  alignas(64) int32_t heightCorrelated[kLaneSlots];  // GgxMasking::HeightCorrelated
  alignas(64) int32_t normalMapped[kLaneSlots], bendsNormalMap[kLaneSlots];
  alignas(64) float tangentX[kLaneSlots], tangentY[kLaneSlots], tangentZ[kLaneSlots], tangentSign[kLaneSlots];
  alignas(64) float texelR[kLaneSlots], texelG[kLaneSlots], texelB[kLaneSlots], normalScale[kLaneSlots];

  // Computed (shadeDiffuseLanes, shadeGltfLanes): the shading normal, for the first-hit layers;
  // glTF: the frame's normal (hitFrameNormal's) and whether a normal map's had to be bent, and in
  // wi* the light sample's direction (for the split by path); next-event
  // estimation and BSDF sampling.
  alignas(64) float snX[kLaneSlots], snY[kLaneSlots], snZ[kLaneSlots];
  alignas(64) float frameX[kLaneSlots], frameY[kLaneSlots], frameZ[kLaneSlots];
  alignas(64) int32_t bent[kLaneSlots];
  alignas(64) int32_t shadowQueued[kLaneSlots];
  alignas(64) float shadowOx[kLaneSlots], shadowOy[kLaneSlots], shadowOz[kLaneSlots], shadowDx[kLaneSlots],
      shadowDy[kLaneSlots], shadowDz[kLaneSlots], shadowTMax[kLaneSlots];
  alignas(64) float directR[kLaneSlots], directG[kLaneSlots], directB[kLaneSlots];  // before the throughput
  alignas(64) int32_t scattered[kLaneSlots];
  alignas(64) float weightR[kLaneSlots], weightG[kLaneSlots], weightB[kLaneSlots], scatterPdf[kLaneSlots];
  alignas(64) float nextOx[kLaneSlots], nextOy[kLaneSlots], nextOz[kLaneSlots], nextDx[kLaneSlots],
      nextDy[kLaneSlots], nextDz[kLaneSlots];
};

// The camera samples of a wave: pixel, the key and index of its sample's stream and pixel corner
// in; each path's keyed sampler (the independent one after the two jitter numbers) and camera ray
// direction out. The same numbers as keying a PathSampler by (streamPixel, sample) and calling
// PinholeCamera::generate one sample at a time.
struct CameraLanes {
  uint32_t count = 0;
  alignas(64) uint64_t pixel[kLaneSlots];
  // What the sampler is keyed by: the pixel, or with --target-error the pixel's stream
  // (error_target.h), and the sample's index in it.
  alignas(64) uint64_t streamPixel[kLaneSlots], sample[kLaneSlots];
  alignas(64) float x[kLaneSlots], y[kLaneSlots];
  alignas(64) uint64_t pixelKey[kLaneSlots];  // the Sobol sampler's (PathSampler::sobolPixelKey)
  alignas(64) PathSampler sampler[kLaneSlots];
  alignas(64) float dirX[kLaneSlots], dirY[kLaneSlots], dirZ[kLaneSlots];
  alignas(64) float filterWeight[kLaneSlots];  // the pixel filter's weight of the sample (1 but for negative lobes)
};
// Lanes [first, last): each sample's position in its pixel drawn through the pixel filter.
void startCameraPaths(CameraLanes& lanes, uint32_t first, uint32_t last, SamplerKind sampler, uint64_t seed,
                      const PinholeCamera& camera, const PixelFilter& filter, bool pixelCentres);

// A texture a lane reads: the texels, what the lane takes from them, and for an albedo the base
// factor they scale (baseFactorAt).
enum class LaneTexture : uint32_t { Albedo, MetallicRoughness, Normal };
struct TexturedLane {
  uint32_t lane;
  LaneTexture use;
  BilinearFootprint footprint;
  Rgb kd;
};

// Lane k's surface at a Lambertian hit of a ray along `direction`, as surfaceAt and bsdfAt give it:
// the position; the vertex normals interpolated, which shadeDiffuseLanes normalizes and turns as
// surfaceAt does; the geometric normal; whether it emits; the albedo, or where a texture scales it,
// its texels requested (prefetched, and added to `textured` for readLaneTextures once every lane
// is fetched: a texel from memory then no longer holds up the next lane).
void fetchLambertianSurface(const Scene& scene, const Hit& hit, Vec3 direction, SurfaceLanes& lanes, uint32_t k,
                            std::vector<TexturedLane>& textured);

// The glTF materials shadeGltfLanes shades: Appendix B's metal/dielectric mix with KHR_materials_ior
// and KHR_materials_specular's factors, normal (bent or as given) and metallic-roughness textures,
// vertex colours. The layers (sheen, clear coat), transmission, volumes and specular textures are
// shaded one hit at a time (PathTracer::shade).
bool gltfShadedInLanes(const Material& m);
// Lane k's surface at a hit of such a material, as surfaceAt and bsdfAt give it: what
// fetchLambertianSurface fetches, the texture coordinates interpolated once for the textures, the
// material's factors and tangents.
void fetchGltfSurface(const Scene& scene, const Hit& hit, Vec3 direction, SurfaceLanes& lanes, uint32_t k,
                      std::vector<TexturedLane>& textured);
// Lane k's lobe (in its shading frame's coordinates), as bsdfAt gives it. Inlined: a call would keep
// shadeGltfLanes' loop from vectorizing.
[[gnu::always_inline]] inline GltfMetalRoughLobe gltfLaneLobe(const SurfaceLanes& l, uint32_t k) {
  return metalRoughLobe({l.kdR[k], l.kdG[k], l.kdB[k]}, l.metallic[k], l.roughness[k], {l.f0R[k], l.f0G[k], l.f0B[k]},
                        l.specular[k], l.heightCorrelated[k] != 0 ? GgxMasking::HeightCorrelated : GgxMasking::Separable);
}
void readLaneTextures(SurfaceLanes& lanes, std::span<const TexturedLane> textured);

// What a lane needs of a light to sample it itself: an emitting triangle seen from one side, of
// constant radiance le, not under a clear coat (sampleChosenLight's triangle case then). Other lights have isTriangle false.
struct LaneLight {
  EmittingTriangle triangle;
  Rgb le;
  bool isTriangle = false;
};
LaneLight laneLight(const Scene& scene, uint32_t light);
void fetchLaneLight(const LaneLight& light, SurfaceLanes& lanes, uint32_t k);

// Lanes [first, last): each lane's shading normal and frame, its light sample's shadow ray and what
// it brings, and the cosine-distributed next direction. One lane at a time ([k, k + 1)) the same
// loop shades single paths, with the same arithmetic.
void shadeDiffuseLanes(SurfaceLanes& lanes, uint32_t first, uint32_t last);
// The same for glTF lanes: the normal texture's shading normal and its frame (bent one lane at a
// time where it must be), next-event estimation and the next direction from the GGX or the cosine
// lobe.
void shadeGltfLanes(SurfaceLanes& lanes, uint32_t first, uint32_t last);

}  // namespace lucent
