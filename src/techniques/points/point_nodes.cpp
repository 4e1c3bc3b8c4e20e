#include "lucent/techniques/points/point_nodes.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace lucent {

namespace {

// Relative radius padding: float rounding of a centre and a length costs a few 2^-24; 2^-20 covers
// it with room, and 21 levels of it grow the root by 2e-5 relative.
constexpr float kSpherePad = 1.0f + 0x1p-20f;
// Absolute cone padding in radians, for the rounding of atan2 and of the new axis.
constexpr float kConePad = 2e-6f;

constexpr int kNormalLattice = kPackedNormalLattice;

// Round to nearest, halves away from zero, inline (std::lround is a library call).
inline int roundToInt(float x) { return int(x + std::copysign(0.5f, x)); }

// An upper bound on the angle between two unit vectors from their chord L = 2 sin(angle / 2):
// angle = 2 asin(L / 2) = L + L^3/24 + 3 L^5/640 + ... <= L + L^3/12 for L <= 1 (about 58 degrees),
// atan2 beyond. Cheaper than angleBetween and as tight as the 8-bit cone code needs.
inline float angleUpperBound(Vec3 a, Vec3 b) {
  const float chord = length(a - b);
  return chord <= 1.0f ? chord + chord * chord * chord * (1.0f / 12.0f) : angleBetween(a, b);
}
constexpr float kAlbedoLevels = 31;  // 5-bit albedo codes
constexpr float kConeLevels = kPackedConeLevels;

uint32_t encodeNormal(Vec3 n) {
  // The decoded normal is the lattice direction k/|k|: only the direction matters, so try every
  // scale whose largest component is 8..15 and keep the closest direction.
  const float m = std::max({std::abs(n.x), std::abs(n.y), std::abs(n.z)});
  int best[3] = {0, 0, kNormalLattice};
  if (!(m > 0)) return uint32_t(kNormalLattice) | uint32_t(kNormalLattice) << 5 | uint32_t(2 * kNormalLattice) << 10;
  // Compare squared cosines, dot^2 / |k|^2: the dot product is positive for every scale.
  float bestCos2 = -1;
  for (int s = kNormalLattice / 2 + 1; s <= kNormalLattice; ++s) {
    int k[3];
    for (int a = 0; a < 3; ++a) k[a] = std::clamp(roundToInt(n[a] / m * float(s)), -kNormalLattice, kNormalLattice);
    const float d = float(k[0]) * n.x + float(k[1]) * n.y + float(k[2]) * n.z;
    const float cos2 = d * d / float(k[0] * k[0] + k[1] * k[1] + k[2] * k[2]);
    if (cos2 > bestCos2) bestCos2 = cos2, best[0] = k[0], best[1] = k[1], best[2] = k[2];
  }
  return uint32_t(best[0] + kNormalLattice) | uint32_t(best[1] + kNormalLattice) << 5 |
         uint32_t(best[2] + kNormalLattice) << 10;
}

uint32_t encodeAlbedoChannel(float a) {
  return uint32_t(roundToInt(std::sqrt(std::clamp(a, 0.0f, 1.0f)) * kAlbedoLevels));
}

}  // namespace

Sphere mergeSpheres(const Sphere& a, const Sphere& b) {
  const Vec3 d = b.center - a.center;
  const float dist = length(d);
  Vec3 center;
  if (dist + b.radius <= a.radius) {
    center = a.center;
  } else if (dist + a.radius <= b.radius) {
    center = b.center;
  } else {
    // The new sphere touches both from outside: its centre lies on the segment, R - ra from a.
    const float r = 0.5f * (dist + a.radius + b.radius);
    center = a.center + d * ((r - a.radius) / dist);
  }
  // The radius that the rounded centre needs, padded, rather than the formula's.
  const float need = std::max(length(a.center - center) + a.radius, length(b.center - center) + b.radius);
  return {center, need * kSpherePad};
}

NormalCone mergeCones(const NormalCone& a, const NormalCone& b) {
  if (a.angle >= kPi || b.angle >= kPi) return {a.axis, kPi};
  const float phi = angleBetween(a.axis, b.axis);
  Vec3 axis;
  if (phi + b.angle <= a.angle) {
    axis = a.axis;
  } else if (phi + a.angle <= b.angle) {
    axis = b.axis;
  } else {
    const float theta = 0.5f * (phi + a.angle + b.angle);
    if (theta >= kPi) return {a.axis, kPi};
    const Vec3 w = b.axis - a.axis * dot(a.axis, b.axis);
    const float wl = length(w);
    if (wl > 1e-6f) {
      // Rotate a's axis towards b's by theta - a.angle, in their common plane.
      const float t = theta - a.angle;
      axis = normalize(a.axis * std::cos(t) + w * (std::sin(t) / wl));
    } else if (dot(a.axis, b.axis) > 0) {
      axis = a.axis;  // parallel within rounding: the verified angle below covers both
    } else {
      // Opposite axes have no common plane to turn in (every perpendicular axis is as good): the
      // full sphere.
      return {a.axis, kPi};
    }
  }
  // The angle that the rounded axis needs, padded.
  const float need = std::max(angleBetween(axis, a.axis) + a.angle, angleBetween(axis, b.axis) + b.angle) + kConePad;
  return {axis, std::min(need, kPi)};
}

Rgb decodeAlbedo(const PackedNode& node) {
  auto channel = [&](int shift) {
    const float v = float((node.normalAlbedo >> shift) & 31u) / kAlbedoLevels;
    return v * v;
  };
  return {channel(15), channel(20), channel(25)};
}

FloatNode decodeNode(const PackedNode& node, const NodeQuantization& q) {
  return {decodeSphere(node, q), {decodeNormal(node), decodeConeAngle(node)}, decodeAlbedo(node)};
}

void encodeSphere(const Sphere& sphere, const NodeQuantization& q, PackedNode& node) {
  for (int a = 0; a < 3; ++a) {
    const float u = (sphere.center[a] - q.origin[a]) / q.step[a];
    node.position[a] = uint16_t(std::clamp(u, 0.0f, 65535.0f) + 0.5f);
  }
  // Enlarge by the centre's displacement, then round up; the decode's own rounding is checked.
  const float need = (sphere.radius + length(decodeCenter(node, q) - sphere.center)) * kSpherePad;
  auto radius = uint32_t(std::ceil(need / q.radiusStep));
  while (float(radius) * q.radiusStep < need) ++radius;
  if (radius > 65535u) throw std::logic_error("point hierarchy: a radius exceeds the packed node's range");
  node.radius = uint16_t(radius);
}

void encodeCone(const NormalCone& cone, PackedNode& node) {
  node.normalAlbedo = (node.normalAlbedo & ~0x7fffu) | encodeNormal(cone.axis);
  uint32_t angle = kConeLevels;
  if (cone.angle < kPi) {
    // An exactly representable axis needs no room for rounding (a leaf on an axis-aligned face
    // keeps a zero cone).
    const float moved = angleUpperBound(decodeNormal(node), cone.axis);
    const float needAngle = cone.angle + (moved > 0 ? moved + kConePad : 0.0f);
    angle = uint32_t(std::min(std::ceil(needAngle / (kPi / kConeLevels)), kConeLevels));
    while (angle < 255u && float(angle) * (kPi / kConeLevels) < needAngle) ++angle;
  }
  node.coneFree = (node.coneFree & ~0xffu) | angle;
}

void encodeAlbedo(Rgb albedo, PackedNode& node) {
  node.normalAlbedo = (node.normalAlbedo & ~(0x7fffu << 15)) | encodeAlbedoChannel(albedo.r) << 15 |
                      encodeAlbedoChannel(albedo.g) << 20 | encodeAlbedoChannel(albedo.b) << 25;
}

PackedNode encodeNode(const Sphere& sphere, const NormalCone& cone, Rgb albedo, const NodeQuantization& q) {
  PackedNode node;
  encodeSphere(sphere, q, node);
  encodeCone(cone, node);
  encodeAlbedo(albedo, node);
  return node;
}

}  // namespace lucent
