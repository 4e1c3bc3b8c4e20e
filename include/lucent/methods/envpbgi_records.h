// The records of the environment-lighting PBGI method's stage dumps (docs/dump-format.md) that another
// backend reads: the radiance caches on the primary visible points.
#pragma once
#include "lucent/core/math.h"

namespace lucent {

inline constexpr int kCacheSide = 5;
inline constexpr int kCacheTexels = kCacheSide * kCacheSide;

// A primary point's cache: irradiance as a function of the receiver's normal, on a 5 x 5 paraboloid
// map of normals in the point's frame (Frame(normal)), from the environment through the buffer's
// empty texels and from the nodes it shows, apart (so that the indirect part can be shown alone).
struct RadianceCache {
  Vec3 position, normal;  // the primary point's surfel
  float radius = 0;       // effective radius: the sphere within which the cache is used
  Rgb environment[kCacheTexels], indirect[kCacheTexels];
};
static_assert(sizeof(RadianceCache) == 628, "RadianceCache is a fixed-size record");

}  // namespace lucent
