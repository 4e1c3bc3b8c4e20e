// The records of the particle-space method's stage dumps (docs/dump-format.md) that another backend
// reads: the area particles.
#pragma once
#include <cstdint>
#include <type_traits>

#include "lucent/core/math.h"

namespace lucent {

// 4.2.1's descriptor, less the light it carries (flux and radiance change with the lights and live
// in arrays of their own).
struct AreaParticle {
  Vec3 position;
  Vec3 normal;      // geometric normal of the side it stands for
  float area;       // Delta A: the surface area it stands for
  Rgb reflectance;  // rho_d: its surface's diffuse reflectance (0 on mirrors and glass)
  uint32_t triangle;
};
static_assert(sizeof(AreaParticle) == 44 && std::is_trivially_copyable_v<AreaParticle>, "dumped as records");

}  // namespace lucent
