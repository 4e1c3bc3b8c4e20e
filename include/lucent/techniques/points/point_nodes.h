// The point hierarchy's node records (Ritschel et al. 2009, 2.1 and 3.1): the full-float node and
// the paper's 128-bit packed node, the merges that build interior nodes from their two children, and
// the packed node's quantization. Plain structs of fixed size that a GPU backend can share.
#pragma once
#include <cstdint>

#include "lucent/core/math.h"

namespace lucent {

struct Sphere {
  Vec3 center;
  float radius = 0;
};

// A cone of normals: every normal below the node is within `angle` (radians) of `axis`;
// angle >= pi means any direction.
struct NormalCone {
  Vec3 axis{0, 0, 1};
  float angle = 0;
};

// Angle between two unit vectors, by atan2 of the cross and dot products: accurate near 0 and pi,
// where acos of the dot product loses half the digits.
inline float angleBetween(Vec3 a, Vec3 b) { return std::atan2(length(cross(a, b)), dot(a, b)); }

// Smallest sphere containing both (exact for two spheres, QSplat-style bounding spheres of 2.1),
// padded by a relative 2^-20 so that it still contains them after float rounding.
Sphere mergeSpheres(const Sphere& a, const Sphere& b);
// Smallest cone containing both cones; opposite normals give the full sphere of directions. Padded
// by 2e-6 radians for float rounding.
NormalCone mergeCones(const NormalCone& a, const NormalCone& b);

// A node in full float: the reference the packed node is measured against. For a leaf, the disc's
// centre and radius, its normal (cone angle 0) and its diffuse albedo; for an interior node, the
// bounding sphere of its children's spheres, the cone of their normals and their area-weighted albedo.
struct FloatNode {
  Sphere sphere;
  NormalCone cone;  // leaves: axis = the disc's normal, angle 0
  Rgb albedo;
};
static_assert(sizeof(FloatNode) == 44, "FloatNode is a fixed-size record shared with GPU backends");

// Where the packed node's 16-bit coordinates are: centre = origin + q * step per axis (the leaves'
// bounding box cut in 65535 steps per axis), radius = q * radiusStep (the largest float radius, with
// 1% slack, cut in 65535 steps).
struct NodeQuantization {
  Vec3 origin;
  Vec3 step{1, 1, 1};
  float radiusStep = 1;
};
static_assert(sizeof(NodeQuantization) == 28, "NodeQuantization is a fixed-size record shared with GPU backends");

// The paper's 128-bit node (3.1): position and radius in 4 x 16 bits, normal and albedo in 3 x 5 bits
// each packed into 32 bits, cone angle in 8 bits, 24 bits (and 2 in normalAlbedo) free. Every
// quantization is conservative where the traversal relies on it: the decoded sphere contains the
// node's children's decoded spheres (and so every leaf disc below), and the decoded cone contains the
// node's float cone (and so every leaf normal below).
struct PackedNode {
  uint16_t position[3] = {0, 0, 0};
  uint16_t radius = 0;
  // Bits 0-14: normal, three 5-bit codes k + 15 of a lattice direction (kx, ky, kz)/|k| with
  // k in -15..15 (axis-aligned normals are exact). Bits 15-29: albedo, three 5-bit codes
  // q = round(31 sqrt(a)), decoded (q/31)^2: square-root coding halves the relative error of dark
  // channels. Bits 30-31 free.
  uint32_t normalAlbedo = 0;
  // Bits 0-7: cone half-angle, ceil(angle / pi * 255) (255: any direction). Bits 8-31 free.
  uint32_t coneFree = 0;
};
static_assert(sizeof(PackedNode) == 16, "the paper's node is 128 bits");

inline constexpr int kPackedNormalLattice = 15;   // normal codes k in -15..15
inline constexpr float kPackedConeLevels = 255;  // 8-bit cone codes over [0, pi]

// The decoders are inline: traversals call them for every node they visit.
inline Vec3 decodeCenter(const PackedNode& node, const NodeQuantization& q) {
  return {q.origin.x + float(node.position[0]) * q.step.x, q.origin.y + float(node.position[1]) * q.step.y,
          q.origin.z + float(node.position[2]) * q.step.z};
}
inline float decodeRadius(const PackedNode& node, const NodeQuantization& q) { return float(node.radius) * q.radiusStep; }
inline Sphere decodeSphere(const PackedNode& node, const NodeQuantization& q) {
  return {decodeCenter(node, q), decodeRadius(node, q)};
}
inline Vec3 decodeNormal(const PackedNode& node) {
  const uint32_t e = node.normalAlbedo;
  return normalize(Vec3{float(int(e & 31u) - kPackedNormalLattice), float(int((e >> 5) & 31u) - kPackedNormalLattice),
                        float(int((e >> 10) & 31u) - kPackedNormalLattice)});
}
inline uint32_t coneCode(const PackedNode& node) { return node.coneFree & 255u; }
inline float decodeConeAngle(const PackedNode& node) { return float(coneCode(node)) * (kPi / kPackedConeLevels); }
Rgb decodeAlbedo(const PackedNode& node);
FloatNode decodeNode(const PackedNode& node, const NodeQuantization& q);

// Packs a node conservatively: the decoded sphere contains `sphere` (centre rounded to nearest, radius
// enlarged by the centre's displacement and rounded up), the decoded cone contains `cone` (angle
// enlarged by the axis's displacement and rounded up). Throws std::logic_error if the radius does not
// fit the quantization (it is sized from the float tree, so it always should).
PackedNode encodeNode(const Sphere& sphere, const NormalCone& cone, Rgb albedo, const NodeQuantization& q);
// encodeNode's three parts, each setting only its own bits, for encoders that share a part between
// nodes (the leaves of one triangle share their normal and cone bits).
void encodeSphere(const Sphere& sphere, const NodeQuantization& q, PackedNode& node);
void encodeCone(const NormalCone& cone, PackedNode& node);
void encodeAlbedo(Rgb albedo, PackedNode& node);

// Reads nodes of either encoding as FloatNode, for code templated on the encoding (traversals).
struct FloatNodeReader {
  const FloatNode* nodes = nullptr;
  FloatNode operator()(uint32_t i) const { return nodes[i]; }
};
struct PackedNodeReader {
  const PackedNode* nodes = nullptr;
  NodeQuantization quantization;
  FloatNode operator()(uint32_t i) const { return decodeNode(nodes[i], quantization); }
};

}  // namespace lucent
