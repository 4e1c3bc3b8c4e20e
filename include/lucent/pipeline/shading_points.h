// The first stage of every method that shades surface points (all but the path tracer): camera
// rays followed through mirrors and glass to the diffuse or glossy surfaces they reach (Purcell et
// al. 2003, section 2.4: "recursive ray tracing for specular reflection and refraction"), in bands
// of image rows.
#pragma once
#include <cstdint>
#include <span>
#include <type_traits>
#include <utility>
#include <vector>

#include "lucent/core/exact_sum.h"
#include "lucent/core/pixel_filter.h"
#include "lucent/core/rng.h"
#include "lucent/core/uninitialized.h"
#include "lucent/pipeline/pixel_rect.h"
#include "lucent/scene/bsdf.h"
#include "lucent/scene/scene.h"
#include "lucent/trace/visibility.h"

namespace lucent {

// Random-number streams of the pipeline's and the methods' stages, so that no two share numbers.
enum class RenderStream : uint64_t { Eye = 1, Direct = 2, Gather = 3, CausticPhotons = 4 };
inline uint64_t streamSeed(uint64_t seed, RenderStream stream) { return hashKey(seed, uint64_t(stream)); }

// A diffuse or glossy surface point that a camera path reached, possibly through specular bounces.
struct ShadingPoint {
  Vec3 position;
  Vec3 geometricNormal;  // counter-clockwise winding normal (for ray offsets)
  Vec3 normal;           // shading normal, on the viewer's side
  Vec3 wo;               // towards the viewer
  Rgb weight;            // camera path throughput up to here
  SurfaceBsdf bsdf;      // not a delta material, non-black; in the frame Frame(normal)
  uint32_t pixel = 0;
  uint32_t sample = 0;   // the camera sample
  uint32_t branch = 0;   // index of this point among its camera sample's (specular splitting)
  uint32_t triangle = 0; // the triangle hit (for methods that keep light per triangle)
  uint32_t medium = kNoMedium;  // the attenuating medium the point lies in, for its shadow and gather rays
};
static_assert(sizeof(ShadingPoint) == 172 && std::is_trivially_copyable_v<ShadingPoint>, "dumped as records");

struct EyePathSettings {
  int spp = 1;  // camera samples per pixel, stratified over the pixel and drawn through its filter
  PixelFilterSettings filter;
  int maxSpecularDepth = 10;
  uint64_t seed = 0;
  bool layers = false;
  PixelRect region;  // the pixels traced (a band of rows, of a crop); empty: the whole image
  int sampleBegin = 0, sampleEnd = 0;  // the camera samples [sampleBegin, sampleEnd) of spp; end 0: spp
  int tileSize = 16;
  // Per pixel of the region (row by row), whether to trace it; empty: every pixel. A pixel left out
  // has no samples.
  std::span<const uint8_t> pixelMask;
};

// Light the film can sum: finite, and within ExactSum's range (a value beyond 10^21 is as
// unusable as a NaN). Samples and points whose light is not are dropped and counted.
inline bool summable(Rgb c) { return ExactSum::accepts(c.r) && ExactSum::accepts(c.g) && ExactSum::accepts(c.b); }

// The first hit of a camera sample, for the layers.
struct FirstHit {
  Rgb albedo;  // reflectance (1 for glass)
  Vec3 normal;  // shading normal
  float depth = 0;
};

// Per pixel, summed over its camera samples (exactly, as the film sums).
struct EyePixel {
  ExactSum emitted[3];   // emission seen directly or through mirrors and glass (and the environment)
  uint32_t validSamples = 0;  // camera samples kept (those with non-finite values are dropped)
  void addSample(Rgb light) {
    ++validSamples;
    for (int c = 0; c < 3; ++c) emitted[c].add(light[c]);
  }
};

// Per pixel, the first hits' reflectance (1 for glass), shading normal and depth, summed over its
// kept camera samples: for the layers only, so held apart (without layers a pixel's sums are a
// third of the memory, which a frame of a million pixels touches for the first time).
struct EyeFeatures {
  ExactSum sums[7];
  void add(const FirstHit& first) {
    const Rgb a = first.albedo;
    const Vec3 n = first.normal;
    const float values[7] = {a.r, a.g, a.b, n.x, n.y, n.z, first.depth};
    for (int c = 0; c < 7; ++c) sums[c].add(values[c]);
  }
};

// The arrays are written by the tiles in parallel (UninitializedVector).
struct EyePaths {
  UninitializedVector<ShadingPoint> points;  // by tile, then pixel, then sample, then branch
  UninitializedVector<EyePixel> pixels;      // the region's, row by row
  UninitializedVector<EyeFeatures> features; // as pixels, with layers; empty without
  PixelRect region;
  // The index in the whole image of the region's i-th pixel.
  uint64_t imagePixel(size_t i, int imageWidth) const {
    const int w = region.width();
    return uint64_t(region.y0 + int(i / size_t(w))) * uint64_t(imageWidth) + uint64_t(region.x0 + int(i % size_t(w)));
  }
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

// What a pixel's centre shows, for the layers by which compare and report break a difference down
// (surface.material, surface.emitter): the first surface the camera ray through the centre hits
// (not followed through mirrors and glass), its material and whether it emits towards the camera;
// where nothing is hit, the background, which emits where the scene has an environment. One code
// per pixel: 0 unknown (not traced), else 2 + the material (1 for the background), with kEmitter
// set where it emits.
struct PixelSurface {
  static constexpr uint32_t kUnknown = 0;
  static constexpr uint32_t kEmitter = 1u << 31;
  static uint32_t code(int material, bool emits) { return uint32_t(material + 2) | (emits ? kEmitter : 0u); }
  static int material(uint32_t code) { return int(code & ~kEmitter) - 2; }  // -1: the background
  static bool emits(uint32_t code) { return (code & kEmitter) != 0; }
};

// What the centre of each pixel of `region` (row by row) shows, as PixelSurface codes: the
// first surface the camera ray hits, its material, and whether it emits towards the camera (its
// emitted radiance there is not black; the background where the scene has an environment).
std::vector<uint32_t> tracePixelSurfaces(const Scene& scene, const Visibility& visibility, const PixelRect& region);


}  // namespace lucent
