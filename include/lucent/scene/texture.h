// Texture and environment lookups.
#pragma once
#include "lucent/core/sampling.h"
#include "lucent/scene/scene.h"

namespace lucent {

// Bilinear lookup with wrap-around; uv (0,0) is the bottom-left corner, as in OBJ.
inline Rgb bilinear(const Rgb* texels, uint32_t width, uint32_t height, float u, float v) {
  const float x = u * width - 0.5f, y = (1.0f - v) * height - 0.5f;
  const float fx = std::floor(x), fy = std::floor(y);
  const float tx = x - fx, ty = y - fy;
  auto wrap = [](long i, uint32_t n) { const long m = i % long(n); return uint32_t(m < 0 ? m + n : m); };
  const uint32_t x0 = wrap(long(fx), width), x1 = wrap(long(fx) + 1, width);
  const uint32_t y0 = wrap(long(fy), height), y1 = wrap(long(fy) + 1, height);
  const Rgb a = texels[size_t(y0) * width + x0] * (1 - tx) + texels[size_t(y0) * width + x1] * tx;
  const Rgb b = texels[size_t(y1) * width + x0] * (1 - tx) + texels[size_t(y1) * width + x1] * tx;
  return a * (1 - ty) + b * ty;
}

inline Rgb diffuseAlbedo(const Scene& scene, const Material& m, Vec2 uv) {
  if (m.kdTexture < 0) return m.kd;
  const Texture& t = scene.textures[m.kdTexture];
  return m.kd * bilinear(&scene.texels[t.offset], t.width, t.height, uv.x, uv.y);
}

// Radiance arriving from the environment along -direction (direction points away from the scene).
// Maps are looked up per texel (nearest), matching the piecewise-constant sampling density exactly.
inline Rgb environmentRadiance(const Environment& env, Vec3 direction) {
  if (!env.present) return Rgb(0.0f);
  if (env.texels.empty()) return env.radiance;
  const Vec2 uv = directionToLatLong(direction);
  const auto x = std::min(uint32_t(uv.x * env.width), env.width - 1);
  const auto y = std::min(uint32_t(uv.y * env.height), env.height - 1);
  return env.texels[size_t(y) * env.width + x];
}

}  // namespace lucent
