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
                       // bit 10: caustic (only specular bounces since the light, at least one);
                       // bits 11-30: facing normal, octahedral, 2 x 10 bits: the geometric normal of
                       // the surface on the side the photon arrived from
};
static_assert(sizeof(Photon) == 32, "Photon is a fixed-size 32-byte record");

inline constexpr uint32_t kPhotonBounceMask = 0xffu;
inline constexpr uint32_t kPhotonAxisShift = 8;
inline constexpr uint32_t kPhotonAxisMask = 3u << kPhotonAxisShift;
inline constexpr uint32_t kPhotonCausticFlag = 1u << 10;
inline constexpr uint32_t kPhotonFacingShift = 11;
inline constexpr int kPhotonFacingBits = 10;

inline uint32_t photonBounce(const Photon& p) { return p.flags & kPhotonBounceMask; }
inline int photonSplitAxis(const Photon& p) { return int((p.flags & kPhotonAxisMask) >> kPhotonAxisShift); }
inline bool photonIsCaustic(const Photon& p) { return (p.flags & kPhotonCausticFlag) != 0; }
inline Vec3 photonIncoming(const Photon& p) { return decodeOctahedral(p.direction); }
inline uint32_t photonFacingBits(Vec3 facingNormal) {
  return encodeOctahedral<kPhotonFacingBits>(facingNormal) << kPhotonFacingShift;
}
inline Vec3 photonFacing(const Photon& p) { return decodeOctahedral<kPhotonFacingBits>(p.flags >> kPhotonFacingShift); }

// Squared distance as every photon map computes it, so that maps and brute force agree to the bit
// on which photons lie inside a radius.
inline float distance2(Vec3 a, Vec3 b) {
  const Vec3 d = a - b;
  return dot(d, d);
}

// Which photons light a surface point's side, the rule of every estimate: those arriving from
// above its shading normal, landed on a surface facing within 60 degrees of its facing normal (its
// geometric normal on the viewer's side), and lying where a surface through the point would put
// them: off its plane by at most what the angle a between the two normals explains, sin(a) of the
// distance (a mesh's neighbouring facet, tilted by a, rises to sin(a) of the distance from the
// point's facet; a smooth surface's chord to sin(a / 2); allowing only sqrt(1 - cos a), 0.71 sin(a),
// left a 24 x 48 sphere's photon estimates 4-10% dark), plus kOffPlane of the distance for the
// rounding of positions. Photons on the far side of a thin wall,
// on another wall where two meet, or on a parallel surface nearby (a panel h above a floor, unless
// farther than h / kOffPlane) do not light the point; without these tests photons on the outside
// of a closed box lit its inside.
inline constexpr float kSameSurfaceCos = 0.5f;
inline constexpr float kOffPlane = 0.01f;
struct SurfaceSide {
  Vec3 shadingNormal;  // on the viewer's side
  Vec3 facingNormal;   // the geometric normal on the viewer's side
};
// incoming: the photon's octahedralDirection (any length); facing: photonFacing(photon); offset:
// the photon's position less the point's, and d2 its squared length (distance2); face: 1 for the
// viewer's side, -1 for the other face (photonLightsThrough).
inline bool photonLightsFace(Vec3 incoming, Vec3 facing, Vec3 offset, float d2, const SurfaceSide& side, float face) {
  const float c = face * dot(facing, side.facingNormal), h = dot(offset, side.facingNormal);
  return (face * dot(incoming, side.shadingNormal) > 0) & (c > kSameSurfaceCos) &
         (h * h <= d2 * (1 - c * c + kOffPlane * kOffPlane));
}
inline bool photonLights(Vec3 incoming, Vec3 facing, Vec3 offset, float d2, const SurfaceSide& side) {
  return photonLightsFace(incoming, facing, offset, d2, side, 1.0f);
}
// Which photons light a transmitting surface point through its surface (a thin wall's other face,
// a volume's inside): those arriving from below its shading normal, landed on the surface's other
// face (facing within 60 degrees of its facing normal turned over), off its tangent plane by no
// more than photonLights allows.
inline bool photonLightsThrough(Vec3 incoming, Vec3 facing, Vec3 offset, float d2, const SurfaceSide& side) {
  return photonLightsFace(incoming, facing, offset, d2, side, -1.0f);
}

}  // namespace lucent
