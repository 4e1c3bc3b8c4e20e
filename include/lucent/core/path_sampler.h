// The random numbers of one camera sample's path, drawn by purpose and bounce: independent
// (PCG32, keyed by seed, pixel and sample) or a padded Owen-scrambled Sobol sequence (Burley 2020,
// "Practical Hash-based Owen Scrambling", as pbrt-v4's PaddedSobolSampler): each pixel's samples
// are the points of a 2D Sobol sequence per pair of dimensions, each pair with its own shuffle of
// the sample index and each dimension its own Owen scramble, all keyed by (seed, pixel); but a
// bounce's light point and the direction the path arrived along share one shuffle, the four
// dimensions of one 4D Sobol sequence (sobolPair). A pixel's first 2^k samples then put one point
// of every other pair in every elementary box of area 2^-k, four light points in every box of area
// 2^(2-k), and eight of the light points with their arrivals in every 4D box of volume 2^(3-k);
// different sets, pixels and seeds are independent; and a sample's numbers depend on its index
// only, so an image does not change with the thread count, the tiles or a split of the samples.
#pragma once
#include <cstdint>

#include "lucent/core/rng.h"
#include "lucent/core/sampler_kind.h"
#include "lucent/core/sobol.h"

namespace lucent {

// What a number is for, at one bounce. Two-dimensional purposes take a pair of dimensions.
enum class SampleUse : uint32_t {
  Roulette = 0,       // Russian roulette on arriving at the bounce (1D)
  Lobe = 1,           // which BSDF lobe (1D)
  LightPoint = 2,     // which light, and the point on it (2D: chooseLight rescales the first)
  BsdfDirection = 4,  // the scattered direction (2D)
};
inline constexpr uint32_t kCameraDimensions = 2;   // the position in the pixel (2D)
inline constexpr uint32_t kBounceDimensions = 6;
// How many dimensions a bounce's light point comes after the direction the path arrived along
// (PathSampler::sobolPair): after the camera's and after the bounce before's BSDF direction alike.
inline constexpr uint32_t kLightPointAfterArrival = kCameraDimensions + uint32_t(SampleUse::LightPoint);

class PathSampler {
 public:
  PathSampler() = default;  // a placeholder until a keyed sampler is assigned
  PathSampler(SamplerKind kind, uint64_t seed, uint64_t pixel, uint64_t sample)
      : index_(uint32_t(sample)), kind_(kind) {
    if (kind == SamplerKind::Sobol) pixelKey_ = sobolPixelKey(seed, pixel);
    else rng_ = Rng(seed, pixel, sample);
  }
  // The Sobol sampler of a pixel whose key (sobolPixelKey) is known.
  static PathSampler sobol(uint64_t pixelKey, uint64_t sample) {
    PathSampler s;
    s.kind_ = SamplerKind::Sobol, s.pixelKey_ = pixelKey, s.index_ = uint32_t(sample);
    return s;
  }
  [[gnu::always_inline]] static uint64_t sobolPixelKey(uint64_t seed, uint64_t pixel) {
    return hashKey(seed, pixel, 0x50b01ull);
  }

  // The position in the pixel.
  Vec2 camera() { return pair(0); }
  float uniform(int bounce, SampleUse use) {
    if (kind_ == SamplerKind::Independent) return rng_.uniform();
    const uint32_t d = dimension(bounce, use);
    const Vec2 p = pair(d & ~1u);
    return d & 1u ? p.y : p.x;
  }
  Vec2 uniform2(int bounce, SampleUse use) {
    if (kind_ == SamplerKind::Independent) return rng_.uniform2();
    return pair(dimension(bounce, use));
  }

  // The dimension of `use` at `bounce` (the camera's are 0 and 1).
  static constexpr uint32_t dimension(int bounce, SampleUse use) {
    return kCameraDimensions + uint32_t(bounce) * kBounceDimensions + uint32_t(use);
  }

  // What the Sobol sampler's numbers depend on: its pixel's key and its sample's index (for
  // sobolPairs, which draws many samplers' pairs at once).
  SamplerKind kind() const { return kind_; }
  uint64_t pixelKey() const { return pixelKey_; }
  uint32_t index() const { return index_; }

  // Dimensions d and d + 1 (d even) of the Sobol sampler whose pixel's key is pixelKey, at sample
  // `index`.
  // A bounce's light point is the second pair of a four-dimensional set whose first pair is the
  // direction the path arrived along, d - kLightPointAfterArrival: the position in the pixel at the
  // first bounce, the bounce before's BSDF direction after it. The light that one bounce brings is an
  // integral over that direction and the next vertex's light point together, and the set stratifies
  // them jointly (on the Cornell box 6-7% less relMSE at 256 and 1,024 samples than two
  // independently shuffled pairs). Every other pair is a set of its own.
  [[gnu::always_inline]] static Vec2 sobolPair(uint64_t pixelKey, uint32_t index, uint32_t d) {
    return sobolPair(pixelKey, index, d, isLightPoint(d));
  }
  static constexpr bool isLightPoint(uint32_t d) { return d % kBounceDimensions == kLightPointAfterArrival; }
  // The same, `second` being isLightPoint(d) (a constant where lanes of one kind are drawn together).
  [[gnu::always_inline]] static Vec2 sobolPair(uint64_t pixelKey, uint32_t index, uint32_t d, bool second) {
    // The set's seeds: the index's shuffle, then each dimension's scramble, each hashed from the one
    // before in 32-bit arithmetic (64-bit multiplies, which a second 64-bit hash would take, are
    // emulated in AVX2 lanes).
    const uint64_t a = mix64(pixelKey + (second ? d - kLightPointAfterArrival : d));
    const uint32_t seedX = uint32_t(a >> 32), seedY = mix32(seedX), seedZ = mix32(seedY), seedW = mix32(seedZ);
    const std::array<uint32_t, 2> v =
        shuffledSobolPair(index, uint32_t(a), second ? seedZ : seedX, second ? seedW : seedY, second);
    return {float(v[0] >> 8) * 0x1p-24f, float(v[1] >> 8) * 0x1p-24f};
  }

 private:
  // Dimensions d and d + 1 (d even). The last pair is kept: a bounce's roulette and lobe share one.
  Vec2 pair(uint32_t d) {
    if (kind_ == SamplerKind::Independent) return rng_.uniform2();
    if (d != lastPair_) lastValues_ = sobolPair(pixelKey_, index_, d), lastPair_ = d;
    return lastValues_;
  }

  Rng rng_;
  uint32_t index_ = 0;
  uint64_t pixelKey_ = 0;
  uint32_t lastPair_ = ~0u;
  Vec2 lastValues_;
  SamplerKind kind_ = SamplerKind::Independent;
};

// The light point's set (PathSampler::sobolPair): its first pair is the camera's at the first bounce
// and the bounce before's BSDF direction later, and no other pair is taken for a light point's.
static_assert(PathSampler::dimension(0, SampleUse::LightPoint) - kLightPointAfterArrival == 0);
static_assert(PathSampler::dimension(3, SampleUse::LightPoint) - kLightPointAfterArrival ==
              PathSampler::dimension(2, SampleUse::BsdfDirection));
static_assert(PathSampler::dimension(3, SampleUse::LightPoint) % kBounceDimensions == kLightPointAfterArrival);
static_assert(PathSampler::dimension(3, SampleUse::Roulette) % kBounceDimensions != kLightPointAfterArrival &&
              PathSampler::dimension(3, SampleUse::BsdfDirection) % kBounceDimensions != kLightPointAfterArrival);

// Many Sobol pairs at once, in SIMD lanes (a pair costs several hashes and bit reversals; in lanes,
// a sixth of the time with AVX-512): (x[k], y[k]) = PathSampler::sobolPair(pixelKey[k], index[k],
// dimension[k]), the same numbers. A light point's pair takes twice the table lookups of another
// (Sobol's dimensions 2 and 3): a batch without one is drawn without them, so callers draw light
// points apart from the other pairs.
void sobolPairs(const uint64_t* pixelKey, const uint32_t* index, const uint32_t* dimension, uint32_t count, float* x,
                float* y);
// The same for the camera's pair of samples starting: pixelKey[k] = PathSampler::sobolPixelKey(seed,
// pixel[k]) and (x[k], y[k]) its sample sample[k]'s dimensions 0 and 1.
void sobolCameraPairs(uint64_t seed, const uint64_t* pixel, const uint64_t* sample, uint32_t count, uint64_t* pixelKey,
                      float* x, float* y);

}  // namespace lucent
