// The sRGB transfer functions (IEC 61966-2-1), shared by textures, PNG output and colour maps.
#pragma once
#include <cmath>

namespace lucent {

inline float srgbToLinear(float v) { return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f); }
inline float linearToSrgb(float v) { return v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f; }

}  // namespace lucent
