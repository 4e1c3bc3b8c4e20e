// The radiance cache on the primary visible points and its interpolation at the pixels (the
// environment-lighting PBGI paper, 3.5, Eq. 5, 4 "Build Radiance Cache", "Calculate Indirect
// Illumination"): each primary point's micro-buffer turned into incoming radiance and pre-convolved
// for the diffuse BRDF on a 5 x 5 map of normals (Scherzer et al. 2012); a screen-space grid of tiles
// listing the caches whose effective sphere overlaps each tile (as Forward+, Harada et al. 2012);
// per pixel the caches of its tile averaged with Ward et al. 1988's weights, clamped by a maximum
// angle.
#pragma once
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "lucent/methods/envpbgi_records.h"
#include "lucent/scene/camera.h"
#include "lucent/scene/scene.h"
#include "methods/envpbgi/env_lighting.h"

namespace lucent {

// The pre-convolution: per cache texel o its normal n_o (the paraboloid direction of its centre,
// clamped to the rim outside the disc) and per buffer texel t the weight max(0, n_o . w_t) dOmega_t.
struct CacheConvolution {
  std::vector<Vec3> normals;    // kCacheTexels
  std::vector<float> weights;   // kCacheTexels x buffer texels, row by cache texel
};
CacheConvolution makeCacheConvolution(const BufferQuadrature& q);

// 4 "Build Radiance Cache": one cache per primary point from its buffer's texels: a texel showing a
// node brings the node's direct light, an empty one the environment.
RadianceCache buildRadianceCache(std::span<const uint32_t> texels, const BufferQuadrature& q,
                                 const CacheConvolution& convolution, const Surfel& surfel, float radius,
                                 const Environment& environment, std::span<const Rgb> nodeDirect);

// The cache's irradiance towards a receiver normal (world): bilinear on the 5 x 5 map, the normal's
// paraboloid point clamped to the disc (normals below the point's horizon read the rim).
// interpolateCaches does the same arithmetic in lanes.
BufferIrradiance cacheIrradiance(const RadianceCache& cache, Vec3 normal);

// The screen's tiles, and per tile the caches whose effective sphere's screen bounds overlap it
// (count, scan, fill: a GPU's CSR arrays), each tile's list in cache order.
struct CacheGrid {
  int tileSize = 16, tilesX = 0, tilesY = 0;
  std::vector<uint32_t> begin;   // tilesX * tilesY + 1
  std::vector<uint32_t> caches;  // cache indices
  // Per cache, its position, radius and Frame(normal) (s, t, n) apart by coordinate: a receiver
  // tests its tile's tens of caches against radius and angle in SIMD lanes (gathering by the
  // tile's indices) before it reads any whole cache.
  std::vector<float> x, y, z, radius;
  std::vector<float> frame[9];
  // Per cache, its centre's view depth (PinholeCamera::project's z) and how far from it in depth a
  // receiver within its radius can be: the radius, widened for the rounding of both depths, which
  // grows with the distance from the eye.
  std::vector<float> depth, depthReach;
  // The tile a receiver at x is shaded in: where x appears, or, where it does not (seen through a
  // mirror, off screen), its pixel's; and x's view depth (PinholeCamera::project's z), from the same
  // projection.
  struct Placement {
    uint32_t tile = 0;
    float depth = 0;
  };
  Placement place(const PinholeCamera& camera, Vec3 x, uint32_t pixel, int width, int height) const;
};
CacheGrid buildCacheGrid(std::span<const RadianceCache> caches, const Camera& camera, int tileSize);

// Forward+'s depth bounds (Harada et al. 2012), per band of receivers: each tile's list cut to the
// caches whose sphere's view-depth range [depth - R, depth + R] meets the depths of the tile's
// receivers in the band. A cache left out has no receiver within its radius (|z_x - z_c| <= |x - c|),
// so Eq. 5 gives the same sums, in the same order, from a fraction of the caches.
struct TileLists {
  std::vector<float> nearest, farthest;  // per tile, its receivers' view depths
  std::vector<uint32_t> count;           // per tile, the cut list's length
  std::vector<uint32_t> caches;          // the cut lists, each at its tile's grid.begin
  std::span<const uint32_t> of(const CacheGrid& grid, uint32_t tile) const {
    return {caches.data() + grid.begin[tile], count[tile]};
  }
};
// The band's receivers are in tiles tileOf[i] at view depths depthOf[i].
void cutTileLists(const CacheGrid& grid, std::span<const uint32_t> tileOf, std::span<const float> depthOf,
                  TileLists& lists);

struct Interpolation {
  float maxAngle = 0;  // radians: caches whose normal is farther from the receiver's are not used
};

// Eq. 5 at a receiver (x, n): of the caches `candidates` (its tile's, or those of them
// cutTileLists kept), those within their radius and the maximum angle, weighted by Ward's
// 1 / (|x - x_k| / R_k + sqrt(1 - n . n_k)), their irradiance towards n averaged; nullopt where none
// qualifies (the receiver then renders a micro-buffer of its own: a cache facing another way, the
// outside of a wall seen from inside, must not lend its light).
std::optional<BufferIrradiance> interpolateCaches(std::span<const RadianceCache> caches, const CacheGrid& grid,
                                                  std::span<const uint32_t> candidates, Vec3 x, Vec3 n,
                                                  const Interpolation& interpolation);

}  // namespace lucent
