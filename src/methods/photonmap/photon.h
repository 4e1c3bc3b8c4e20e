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
  uint32_t flags;      // bounce count in the low byte; bits 8-9: kd-tree split axis (PhotonKdTree);
                       // bit 10: caustic (only specular bounces since the light, at least one)
};
static_assert(sizeof(Photon) == 32, "Photon is a fixed-size 32-byte record");

inline constexpr uint32_t kPhotonBounceMask = 0xffu;
inline constexpr uint32_t kPhotonAxisShift = 8;
inline constexpr uint32_t kPhotonAxisMask = 3u << kPhotonAxisShift;
inline constexpr uint32_t kPhotonCausticFlag = 1u << 10;

inline uint32_t photonBounce(const Photon& p) { return p.flags & kPhotonBounceMask; }
inline int photonSplitAxis(const Photon& p) { return int((p.flags & kPhotonAxisMask) >> kPhotonAxisShift); }
inline bool photonIsCaustic(const Photon& p) { return (p.flags & kPhotonCausticFlag) != 0; }
inline Vec3 photonIncoming(const Photon& p) { return decodeOctahedral(p.direction); }

// Squared distance as every photon map computes it, so that maps and brute force agree to the bit
// on which photons lie inside a radius.
inline float distance2(Vec3 a, Vec3 b) {
  const Vec3 d = a - b;
  return dot(d, d);
}

}  // namespace lucent
