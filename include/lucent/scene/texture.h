// Texture and environment lookups.
#pragma once
#include <array>
#include <cmath>

#include "lucent/core/sampling.h"
#include "lucent/core/srgb.h"
#include "lucent/scene/scene.h"

namespace lucent {

// Linear value of every 8-bit sRGB code (colour textures), and of every 8-bit code of a texture
// that holds data, not colour (glTF's metallic-roughness and normal textures are linear).
inline const std::array<float, 256> kSrgb8ToLinear = [] {
  std::array<float, 256> table{};
  for (int i = 0; i < 256; ++i) table[i] = srgbToLinear(i / 255.0f);
  return table;
}();
inline const std::array<float, 256> kUnorm8ToFloat = [] {
  std::array<float, 256> table{};
  for (int i = 0; i < 256; ++i) table[i] = i / 255.0f;
  return table;
}();

inline Rgb decodeTexel(uint32_t texel, const std::array<float, 256>& decode = kSrgb8ToLinear) {
  return {decode[texel & 0xff], decode[(texel >> 8) & 0xff], decode[(texel >> 16) & 0xff]};
}

// The four texels a bilinear lookup reads (wrapping around) and the weights between them; uv (0,0)
// is the bottom-left corner, as in OBJ.
struct BilinearFootprint {
  const uint32_t* row0;
  const uint32_t* row1;
  uint32_t x0, x1;
  float tx, ty;
};
// A coordinate c in image units (texel centres at k + 0.5) of an image `size` texels wide, under a
// clamping or mirroring wrap: the two texels it lies between and the weight of the second.
struct TexelPair {
  uint32_t first, second;
  float weight;
};
inline TexelPair boundedTexels(float c, uint32_t size, TextureWrap wrap) {
  if (wrap == TextureWrap::Mirror) {
    // Period 2 in texture units: [0, 1] then back.
    const float period = 2.0f * float(size), m = c - period * std::floor(c / period);
    c = m > float(size) ? period - m : m;
  }
  const float x = std::clamp(c, 0.5f, float(size) - 0.5f) - 0.5f;
  const uint32_t first = std::min(uint32_t(x), size - 1);
  return {first, std::min(first + 1, size - 1), x - float(first)};
}

inline BilinearFootprint bilinearFootprint(const Texture& t, const uint32_t* texels, Vec2 uv) {
  const float x = (uv.x - std::floor(uv.x)) * t.width - 0.5f;
  const float y = (std::ceil(uv.y) - uv.y) * t.height - 0.5f;
  const float fx = std::floor(x), fy = std::floor(y);
  // x lies in [-0.5, width - 0.5], so wrapping needs only the two edge cases.
  uint32_t x0 = fx < 0 ? t.width - 1 : std::min(uint32_t(fx), t.width - 1);
  uint32_t y0 = fy < 0 ? t.height - 1 : std::min(uint32_t(fy), t.height - 1);
  uint32_t x1 = x0 + 1 == t.width ? 0 : x0 + 1, y1 = y0 + 1 == t.height ? 0 : y0 + 1;
  float tx = x - fx, ty = y - fy;
  if (t.wrapU != TextureWrap::Repeat || t.wrapV != TextureWrap::Repeat || t.nearest) {
    // glTF's samplers: a clamped or mirrored axis replaces the repeated one (image y runs along
    // 1 - v: Lucent's v runs up); nearest keeps the texel holding the point.
    if (t.wrapU != TextureWrap::Repeat) {
      const TexelPair p = boundedTexels(uv.x * float(t.width), t.width, t.wrapU);
      x0 = p.first, x1 = p.second, tx = p.weight;
    }
    if (t.wrapV != TextureWrap::Repeat) {
      const TexelPair p = boundedTexels((1.0f - uv.y) * float(t.height), t.height, t.wrapV);
      y0 = p.first, y1 = p.second, ty = p.weight;
    }
    if (t.nearest) {
      x0 = x1 = tx < 0.5f ? x0 : x1;
      y0 = y1 = ty < 0.5f ? y0 : y1;
      tx = ty = 0.0f;
    }
  }
  return {texels + t.offset + size_t(y0) * t.width, texels + t.offset + size_t(y1) * t.width, x0, x1, tx, ty};
}

// Bilinear lookup of the decoded texels (linear for sRGB colour), with wrap-around.
inline Rgb bilinear(const BilinearFootprint& f, const std::array<float, 256>& decode = kSrgb8ToLinear) {
  const Rgb a = decodeTexel(f.row0[f.x0], decode) * (1 - f.tx) + decodeTexel(f.row0[f.x1], decode) * f.tx;
  const Rgb b = decodeTexel(f.row1[f.x0], decode) * (1 - f.tx) + decodeTexel(f.row1[f.x1], decode) * f.tx;
  return a * (1 - f.ty) + b * f.ty;
}
inline Rgb bilinear(const Texture& t, const uint32_t* texels, Vec2 uv) {
  return bilinear(bilinearFootprint(t, texels, uv));
}

// Bilinear lookup of the A channel (linear: coverage, not colour).
inline float bilinearAlpha(const BilinearFootprint& f) {
  const auto a = [](uint32_t texel) { return float(texel >> 24) * (1.0f / 255.0f); };
  return (a(f.row0[f.x0]) * (1 - f.tx) + a(f.row0[f.x1]) * f.tx) * (1 - f.ty) +
         (a(f.row1[f.x0]) * (1 - f.tx) + a(f.row1[f.x1]) * f.tx) * f.ty;
}

// A material's alpha at texture coordinates uv: its base alpha times its colour texture's A.
inline float surfaceAlpha(const Scene& scene, const Material& m, Vec2 uv) {
  if (m.kdTexture < 0) return m.baseAlpha;
  return m.baseAlpha * bilinearAlpha(bilinearFootprint(scene.textures[m.kdTexture], scene.texels.data(), uv));
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
