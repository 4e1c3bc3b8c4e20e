// The sRGB transfer functions (IEC 61966-2-1), shared by textures, PNG output and colour maps.
#pragma once
#include <cmath>
#include <cstdint>

namespace lucent {

inline float srgbToLinear(float v) { return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f); }
inline float linearToSrgb(float v) { return v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f; }
// The nearest 8-bit code of a linear value in [0, 1].
inline uint8_t linearToSrgb8(float v) { return static_cast<uint8_t>(std::lround(255.0f * linearToSrgb(v))); }

}  // namespace lucent
