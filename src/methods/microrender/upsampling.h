// Bilateral upsampling (Ritschel et al. 2009, 2.4; weights after Sloan et al. 2007): indirect light
// gathered at the pixels of a coarser lattice is interpolated to the others with bilinear weights
// times a normal and a plane-distance weight, so that it does not cross silhouettes or creases;
// where the weights vanish, the pixel is gathered itself.
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "lucent/pipeline/shading_points.h"

namespace lucent {

// The lattice of gathered pixels: every `step`-th pixel in x and y (step 2: 1/4 of the pixels,
// step 4: 1/16).
inline bool onGatherLattice(uint32_t pixel, int width, int step) {
  return (pixel % uint32_t(width)) % uint32_t(step) == 0 && (pixel / uint32_t(width)) % uint32_t(step) == 0;
}

struct UpsamplingSettings {
  int width = 0, height = 0, step = 1;
  Vec3 eye;
  float pixelAngle = 0;  // the camera's angle per pixel (its footprint at distance z is z * pixelAngle)
};

// For each point not on the lattice, its indirect light interpolated from the lattice points of the
// same camera sample at the four lattice pixels around it (so that a part of a render's samples
// interpolates as the whole render does), demodulated by reflectance (so textures stay sharp) and modulated
// by its own; returns the points whose weights summed to nearly zero, left for gathering.
std::vector<uint32_t> upsampleIndirect(std::span<const ShadingPoint> points, const UpsamplingSettings& settings,
                                       std::span<Rgb> indirect);

}  // namespace lucent
