#include "methods/envpbgi/radiance_cache.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "lucent/core/lane_clones.h"
#include "lucent/core/stop.h"
#include "lucent/scene/texture.h"
#include "lucent/techniques/microbuffers/micro_buffer.h"

namespace lucent {

namespace {

// The centre of cache texel i along an axis of [-1, 1].
float cacheTexelCentre(int i) { return -1.0f + (2.0f * float(i) + 1.0f) / float(kCacheSide); }

}  // namespace

CacheConvolution makeCacheConvolution(const BufferQuadrature& q) {
  CacheConvolution c;
  c.normals.resize(kCacheTexels);
  c.weights.assign(size_t(kCacheTexels) * q.texels(), 0.0f);
  for (int y = 0; y < kCacheSide; ++y)
    for (int x = 0; x < kCacheSide; ++x) {
      Vec2 p{cacheTexelCentre(x), cacheTexelCentre(y)};
      const float r = std::sqrt(p.x * p.x + p.y * p.y);
      if (r > 1.0f) p = {p.x / r, p.y / r};
      const Vec3 normal = paraboloidDirection(p);
      const size_t o = size_t(y) * kCacheSide + size_t(x);
      c.normals[o] = normal;
      for (const uint16_t t : q.mapping.used) {
        const Vec3 w = q.mapping.direction[t];
        const float solidAngle = q.cosineWeight[t] / w.z;
        c.weights[o * q.texels() + t] = std::max(0.0f, dot(normal, w)) * solidAngle;
      }
    }
  return c;
}

RadianceCache buildRadianceCache(std::span<const uint32_t> texels, const BufferQuadrature& q,
                                 const CacheConvolution& convolution, const Surfel& surfel, float radius,
                                 const Environment& environment, std::span<const Rgb> nodeDirect) {
  RadianceCache cache;
  cache.position = surfel.position;
  cache.normal = surfel.normal;
  cache.radius = radius;
  // Incoming radiance per texel and channel (environment R, G, B, then the nodes'; 0 at unused
  // texels), then the fixed linear map to the 25 normals: over every texel in eight interleaved
  // partial sums, which vectorize and add up in a fixed order.
  const Frame frame(surfel.normal);
  const uint32_t n = q.texels();
  alignas(64) float incoming[6][kMaxMicroBufferSide * kMaxMicroBufferSide];
  for (auto& channel : incoming) std::fill_n(channel, n, 0.0f);
  for (const uint16_t t : q.mapping.used) {
    const uint32_t texel = texels[t];
    const Rgb e = texel == kEmptyMicroPixel ? environmentRadiance(environment, frame.toWorld(q.mapping.direction[t])) : Rgb();
    const Rgb d = microPixelShowsNode(texel) ? nodeDirect[microPixelNode(texel)] : Rgb();
    for (int c = 0; c < 3; ++c) incoming[c][t] = e[c], incoming[3 + c][t] = d[c];
  }
  constexpr uint32_t kLanes = 8;
  const uint32_t whole = n / kLanes * kLanes;
  for (int o = 0; o < kCacheTexels; ++o) {
    const float* w = &convolution.weights[size_t(o) * n];
    float sums[6];
    for (int c = 0; c < 6; ++c) {
      float partial[kLanes] = {};
      for (uint32_t t = 0; t < whole; t += kLanes)
        for (uint32_t k = 0; k < kLanes; ++k) partial[k] += incoming[c][t + k] * w[t + k];
      float sum = 0;
      for (uint32_t t = whole; t < n; ++t) sum += incoming[c][t] * w[t];
      for (const float p : partial) sum += p;
      sums[c] = sum;
    }
    cache.environment[o] = {sums[0], sums[1], sums[2]};
    cache.indirect[o] = {sums[3], sums[4], sums[5]};
  }
  return cache;
}

BufferIrradiance cacheIrradiance(const RadianceCache& cache, Vec3 normal) {
  const Vec3 local = Frame(cache.normal).toLocal(normal);
  // The paraboloid point, clamped to the disc (for normals at or below the horizon, the rim).
  Vec2 p = local.z > -0.999f ? paraboloidPoint(local) : Vec2{local.x, local.y};
  const float r = std::sqrt(p.x * p.x + p.y * p.y);
  if (r > 1.0f) p = {p.x / r, p.y / r};
  // Bilinear between the texel centres (clamped to the outer ones).
  auto coordinate = [](float v, int& i0, float& f) {
    const float s = std::clamp((v + 1.0f) * 0.5f * float(kCacheSide) - 0.5f, 0.0f, float(kCacheSide - 1));
    i0 = std::min(int(s), kCacheSide - 2);
    f = s - float(i0);
  };
  int x0, y0;
  float fx, fy;
  coordinate(p.x, x0, fx);
  coordinate(p.y, y0, fy);
  BufferIrradiance e;
  const float w[4] = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
  const int at[4] = {y0 * kCacheSide + x0, y0 * kCacheSide + x0 + 1, (y0 + 1) * kCacheSide + x0,
                     (y0 + 1) * kCacheSide + x0 + 1};
  for (int k = 0; k < 4; ++k) e.environment += cache.environment[at[k]] * w[k], e.nodes += cache.indirect[at[k]] * w[k];
  return e;
}

CacheGrid buildCacheGrid(std::span<const RadianceCache> caches, const Camera& cameraSettings, int tileSize) {
  const PinholeCamera camera(cameraSettings);
  CacheGrid g;
  g.tileSize = tileSize;
  g.tilesX = (cameraSettings.width + tileSize - 1) / tileSize;
  g.tilesY = (cameraSettings.height + tileSize - 1) / tileSize;
  // Each cache's tile rectangle [x0, x1] x [y0, y1], or empty.
  struct TileRect {
    int x0 = 1, y0 = 1, x1 = 0, y1 = 0;
  };
  std::vector<TileRect> rects(caches.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, caches.size(), 1024), [&](const tbb::blocked_range<size_t>& r) {
    stopPoint();
    for (size_t k = r.begin(); k != r.end(); ++k) {
      const RadianceCache& c = caches[k];
      const Vec3 p = camera.project(c.position);
      TileRect& t = rects[k];
      if (p.z <= c.radius) {
        // The sphere reaches the eye's plane: it may cover any part of the screen (unless wholly behind).
        if (p.z >= -c.radius) t = {0, 0, g.tilesX - 1, g.tilesY - 1};
        continue;
      }
      const float footprint = camera.sphereFootprint(c.position, c.radius);
      const float x0 = p.x - footprint, x1 = p.x + footprint, y0 = p.y - footprint, y1 = p.y + footprint;
      if (x1 < 0 || y1 < 0 || x0 >= float(cameraSettings.width) || y0 >= float(cameraSettings.height)) continue;
      auto tile = [&](float v, int count) { return std::clamp(int(std::floor(v / float(tileSize))), 0, count - 1); };
      t = {tile(x0, g.tilesX), tile(y0, g.tilesY), tile(x1, g.tilesX), tile(y1, g.tilesY)};
    }
  });
  // Count, scan, fill; a row of tiles per work item, each tile's list in cache order.
  const size_t tiles = size_t(g.tilesX) * size_t(g.tilesY);
  std::vector<uint32_t> counts(tiles, 0);
  auto eachRowOfTiles = [&](auto&& visit) {
    tbb::parallel_for(0, g.tilesY, [&](int y) {
      stopPoint();
      for (size_t k = 0; k < caches.size(); ++k)
        if (rects[k].y0 <= y && y <= rects[k].y1)
          for (int x = rects[k].x0; x <= rects[k].x1; ++x) visit(size_t(y) * size_t(g.tilesX) + size_t(x), k);
    });
  };
  eachRowOfTiles([&](size_t tile, size_t) { ++counts[tile]; });
  g.begin.assign(tiles + 1, 0);
  for (size_t i = 0; i < tiles; ++i) g.begin[i + 1] = g.begin[i] + counts[i];
  g.caches.resize(g.begin[tiles]);
  std::vector<uint32_t> cursor(g.begin.begin(), g.begin.end() - 1);
  eachRowOfTiles([&](size_t tile, size_t k) { g.caches[cursor[tile]++] = uint32_t(k); });
  for (std::vector<float>* v : {&g.x, &g.y, &g.z, &g.radius, &g.depth, &g.depthReach}) v->resize(caches.size());
  for (std::vector<float>& v : g.frame) v.resize(caches.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, caches.size(), 1024), [&](const tbb::blocked_range<size_t>& r) {
    stopPoint();
    for (size_t k = r.begin(); k != r.end(); ++k) {
      const RadianceCache& c = caches[k];
      g.x[k] = c.position.x, g.y[k] = c.position.y, g.z[k] = c.position.z, g.radius[k] = c.radius;
      g.depth[k] = camera.project(c.position).z;
      // A thousandth of the radius and of the distance from the eye (a receiver within the radius
      // is no farther from the eye than that distance plus the radius).
      g.depthReach[k] = c.radius * 1.001f + 1e-3f * std::max(1.0f, length(c.position - cameraSettings.eye) + c.radius);
      const Frame f(c.normal);
      const float axes[9] = {f.s.x, f.s.y, f.s.z, f.t.x, f.t.y, f.t.z, f.n.x, f.n.y, f.n.z};
      for (int a = 0; a < 9; ++a) g.frame[a][k] = axes[a];
    }
  });
  return g;
}

CacheGrid::Placement CacheGrid::place(const PinholeCamera& camera, Vec3 x, uint32_t pixel, int width,
                                     int height) const {
  const Vec3 s = camera.project(x);
  const bool onScreen = s.z > 0 && s.x >= 0 && s.y >= 0 && s.x < float(width) && s.y < float(height);
  const int px = onScreen ? int(s.x) : int(pixel % uint32_t(width));
  const int py = onScreen ? int(s.y) : int(pixel / uint32_t(width));
  return {uint32_t(py / tileSize) * uint32_t(tilesX) + uint32_t(px / tileSize), s.z};
}

void cutTileLists(const CacheGrid& grid, std::span<const uint32_t> tileOf, std::span<const float> depthOf,
                  TileLists& lists) {
  const size_t tiles = size_t(grid.tilesX) * size_t(grid.tilesY);
  lists.nearest.assign(tiles, kInf);
  lists.farthest.assign(tiles, -kInf);
  lists.count.assign(tiles, 0);
  lists.caches.resize(grid.caches.size());
  bool any = false;
  for (size_t i = 0; i < tileOf.size(); ++i) {
    const uint32_t t = tileOf[i];
    // A NaN depth widens nothing (its receiver qualifies for no cache).
    lists.nearest[t] = std::min(lists.nearest[t], depthOf[i]), lists.farthest[t] = std::max(lists.farthest[t], depthOf[i]);
    any = true;
  }
  if (!any) return;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, tiles, 16), [&](const tbb::blocked_range<size_t>& r) {
    stopPoint();
    for (size_t t = r.begin(); t != r.end(); ++t) {
      if (!(lists.nearest[t] <= lists.farthest[t])) continue;
      uint32_t kept = 0;
      for (uint32_t j = grid.begin[t]; j < grid.begin[t + 1]; ++j) {
        const uint32_t c = grid.caches[j];
        lists.caches[grid.begin[t] + kept] = c;
        kept += grid.depth[c] - grid.depthReach[c] <= lists.farthest[t] &&
                grid.depth[c] + grid.depthReach[c] >= lists.nearest[t];
      }
      lists.count[t] = kept;
    }
  });
}

namespace {

// Eq. 5's test of a block of a tile's caches at a receiver (x, n), in lanes: weight[k] is Ward's
// 1 / (|x - x_k| / R_k + sqrt(1 - n . n_k)) where cache k is within its radius and the maximum
// angle, else 0 (a qualifying cache's weight is at least 1 / (1 + sqrt 2)). The same arithmetic
// as length(), dot() and wardError().
LUCENT_LANE_LOOP(void, wardWeights, (const CacheGrid& __restrict g, const uint32_t* __restrict cache, uint32_t count,
                                     Vec3 x, Vec3 n, float cosMax, float* __restrict weight)) {
  const float *cx = g.x.data(), *cy = g.y.data(), *cz = g.z.data(), *cr = g.radius.data();
  const float *nx = g.frame[6].data(), *ny = g.frame[7].data(), *nz = g.frame[8].data();
  for (uint32_t k = 0; k < count; ++k) {
    const uint32_t c = cache[k];
    const float dx = x.x - cx[c], dy = x.y - cy[c], dz = x.z - cz[c];
    const float distance = std::sqrt(dx * dx + dy * dy + dz * dz);
    const float cosine = n.x * nx[c] + n.y * ny[c] + n.z * nz[c];
    const bool qualifies = (distance < cr[c]) & (cosine >= cosMax);
    const float ward = distance / cr[c] + std::sqrt(std::max(0.0f, 1.0f - cosine));
    weight[k] = qualifies ? 1.0f / std::max(ward, 1e-6f) : 0.0f;
  }
}
LUCENT_LANE_VERSIONS(void, wardWeights,
                     (const CacheGrid& __restrict g, const uint32_t* __restrict cache, uint32_t count, Vec3 x, Vec3 n,
                      float cosMax, float* __restrict weight),
                     (g, cache, count, x, n, cosMax, weight))

// Where a receiver's normal falls on each qualifying cache's 5 x 5 map: cacheIrradiance's
// arithmetic in lanes.
constexpr uint32_t kCacheBlock = 64;
struct MapLookups {
  uint32_t count = 0;
  uint32_t cache[kCacheBlock];
  float weight[kCacheBlock];
  int32_t x0[kCacheBlock], y0[kCacheBlock];
  float fx[kCacheBlock], fy[kCacheBlock];
};
LUCENT_LANE_LOOP(void, locateOnMaps, (MapLookups& __restrict m, const CacheGrid& __restrict g, Vec3 n)) {
  const float* f[9];
  for (int a = 0; a < 9; ++a) f[a] = g.frame[a].data();
  for (uint32_t k = 0; k < m.count; ++k) {
    const uint32_t c = m.cache[k];
    const float lx = n.x * f[0][c] + n.y * f[1][c] + n.z * f[2][c];
    const float ly = n.x * f[3][c] + n.y * f[4][c] + n.z * f[5][c];
    const float lz = n.x * f[6][c] + n.y * f[7][c] + n.z * f[8][c];
    // The paraboloid point, clamped to the disc (for normals at or below the horizon, the rim).
    const bool above = lz > -0.999f;
    float px = above ? lx / (1.0f + lz) : lx, py = above ? ly / (1.0f + lz) : ly;
    const float r = std::sqrt(px * px + py * py);
    px = r > 1.0f ? px / r : px, py = r > 1.0f ? py / r : py;
    // Bilinear between the texel centres (clamped to the outer ones).
    const float sx = std::clamp((px + 1.0f) * 0.5f * float(kCacheSide) - 0.5f, 0.0f, float(kCacheSide - 1));
    const float sy = std::clamp((py + 1.0f) * 0.5f * float(kCacheSide) - 0.5f, 0.0f, float(kCacheSide - 1));
    m.x0[k] = std::min(int32_t(sx), int32_t(kCacheSide - 2));
    m.y0[k] = std::min(int32_t(sy), int32_t(kCacheSide - 2));
    m.fx[k] = sx - float(m.x0[k]);
    m.fy[k] = sy - float(m.y0[k]);
  }
}
LUCENT_LANE_VERSIONS(void, locateOnMaps, (MapLookups& __restrict m, const CacheGrid& __restrict g, Vec3 n), (m, g, n))

}  // namespace

std::optional<BufferIrradiance> interpolateCaches(std::span<const RadianceCache> caches, const CacheGrid& grid,
                                                  std::span<const uint32_t> candidates, Vec3 x, Vec3 n,
                                                  const Interpolation& interpolation) {
  const float cosMax = std::cos(interpolation.maxAngle);
  BufferIrradiance sum;
  double total = 0;
  MapLookups m;
  for (uint32_t block = 0; block < candidates.size(); block += kCacheBlock) {
    const uint32_t count = std::min(kCacheBlock, uint32_t(candidates.size()) - block);
    float weight[kCacheBlock];
    wardWeights(grid, &candidates[block], count, x, n, cosMax, weight);
    // The qualifying ones, without a branch per cache.
    m.count = 0;
    for (uint32_t k = 0; k < count; ++k)
      m.cache[m.count] = candidates[block + k], m.weight[m.count] = weight[k], m.count += weight[k] > 0;
    locateOnMaps(m, grid, n);
    for (uint32_t k = 0; k < m.count; ++k) {
      const RadianceCache& c = caches[m.cache[k]];
      const float fx = m.fx[k], fy = m.fy[k];
      const float w[4] = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
      const int at = m.y0[k] * kCacheSide + m.x0[k];
      const int texel[4] = {at, at + 1, at + kCacheSide, at + kCacheSide + 1};
      BufferIrradiance e;
      for (int j = 0; j < 4; ++j) e.environment += c.environment[texel[j]] * w[j], e.nodes += c.indirect[texel[j]] * w[j];
      sum.environment += e.environment * m.weight[k], sum.nodes += e.nodes * m.weight[k];
      total += m.weight[k];
    }
  }
  if (total > 0) {
    const float inv = float(1.0 / total);
    return BufferIrradiance{sum.environment * inv, sum.nodes * inv};
  }
  return std::nullopt;  // no cache qualifies
}

}  // namespace lucent
