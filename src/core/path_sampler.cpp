#include "lucent/core/path_sampler.h"

#include "lucent/core/lane_clones.h"

namespace lucent {

LUCENT_LANE_LOOP(void, sobolPairs, (const uint64_t* __restrict pixelKey, const uint32_t* __restrict index,
                                    const uint32_t* __restrict dimension, uint32_t count, float* __restrict x,
                                    float* __restrict y)) {
  int lightPoints = 0;
  for (uint32_t k = 0; k < count; ++k) lightPoints += PathSampler::isLightPoint(dimension[k]) ? 1 : 0;
  if (lightPoints == 0) {
    for (uint32_t k = 0; k < count; ++k) {
      const Vec2 p = PathSampler::sobolPair(pixelKey[k], index[k], dimension[k], false);
      x[k] = p.x, y[k] = p.y;
    }
    return;
  }
  for (uint32_t k = 0; k < count; ++k) {
    const Vec2 p = PathSampler::sobolPair(pixelKey[k], index[k], dimension[k]);
    x[k] = p.x, y[k] = p.y;
  }
}
LUCENT_LANE_VERSIONS(void, sobolPairs,
                     (const uint64_t* __restrict pixelKey, const uint32_t* __restrict index,
                      const uint32_t* __restrict dimension, uint32_t count, float* __restrict x, float* __restrict y),
                     (pixelKey, index, dimension, count, x, y))

LUCENT_LANE_LOOP(void, sobolCameraPairs, (uint64_t seed, const uint64_t* __restrict pixel,
                                          const uint64_t* __restrict sample, uint32_t count,
                                          uint64_t* __restrict pixelKey, float* __restrict x, float* __restrict y)) {
  for (uint32_t k = 0; k < count; ++k) {
    const uint64_t key = PathSampler::sobolPixelKey(seed, pixel[k]);
    const Vec2 p = PathSampler::sobolPair(key, uint32_t(sample[k]), 0);
    pixelKey[k] = key, x[k] = p.x, y[k] = p.y;
  }
}
LUCENT_LANE_VERSIONS(void, sobolCameraPairs,
                     (uint64_t seed, const uint64_t* __restrict pixel, const uint64_t* __restrict sample,
                      uint32_t count, uint64_t* __restrict pixelKey, float* __restrict x, float* __restrict y),
                     (seed, pixel, sample, count, pixelKey, x, y))

}  // namespace lucent
