// The photon record shared with GPU backends.
#pragma once
#include <cstdint>

#include "lucent/core/math.h"
#include "lucent/core/octahedral.h"

namespace lucent {

struct Photon {
  Vec3 position;
  Rgb power;           // flux carried, W
  uint32_t direction;  // octahedral unit vector towards where the photon came from, 2 x 16 bits
  uint32_t flags;      // bounce count in the low byte
};
static_assert(sizeof(Photon) == 32, "Photon is a fixed-size 32-byte record");

}  // namespace lucent
