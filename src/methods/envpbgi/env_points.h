// The point hierarchy as the environment-lighting PBGI paper stores it (section 4, "Data
// structure"): 48-byte unquantized nodes with two child indices, a skip index for stackless
// traversal and a 32-bit selection field, over the shared point hierarchy (src/techniques/points). Also
// per node the surface point a micro-buffer is rendered from (its leaves' area-weighted mean
// position and normal) and the flags of the selection.
#pragma once
#include <cstdint>
#include <vector>

#include "lucent/core/math.h"
#include "lucent/techniques/points/point_hierarchy.h"

namespace lucent {

// Section 4: position, radius, normal and cone angle (the bounding sphere and the cone of normals,
// 32 bytes, unquantized), two child indices, a skip index and the selection field: 48 bytes.
struct EnvPointNode {
  Vec3 position;        // the bounding sphere's centre
  float radius = 0;
  Vec3 normal;          // the normal cone's axis
  float coneAngle = 0;  // half-angle, radians; pi or more: any direction
  uint32_t child[2] = {0, 0};  // 0 for leaves
  uint32_t skip = 0;           // the node after the subtree in depth-first order; kTraversalEnd after the last
  uint32_t selection = 0;      // EnvSelection bits
};
static_assert(sizeof(EnvPointNode) == 48, "the paper's node is 48 bytes");

// The selection field's bits (3.3, 3.4, Fig. 3).
enum EnvSelection : uint32_t {
  kPrimary = 1u << 0,       // a primary visible point: on the camera's cut, visible
  kSecondary = 1u << 1,     // a secondary visible point: seen in a primary point's micro-buffer
  kCovered = 1u << 2,       // its direct light follows from itself or its descendants (upward traversal)
  kDerivable = 1u << 3,     // a secondary point whose direct light is its children's mean
  kUnderPrimary = 1u << 4,  // below a primary point: its direct light is the primary point's (downward)
  kOwnBuffer = 1u << 5,     // its direct light is computed by a micro-buffer of its own
  kHasDirect = 1u << 6,     // holds direct light after propagation
};

// A node's surface point: its leaves' area-weighted mean position and the normalized area-weighted
// mean of their normals (the cone's axis where they cancel). Micro-buffers are rendered from here:
// a curved node's sphere centre lies off its surface (notes A5).
struct Surfel {
  Vec3 position, normal;
};
static_assert(sizeof(Surfel) == 24, "Surfel is a fixed-size record");

struct EnvHierarchy {
  PointHierarchy points;             // float encoding: the nodes' spheres, cones, albedo and areas
  std::vector<EnvPointNode> nodes;   // by heap number (node_tree.h), entry 0 unused
  std::vector<Surfel> surfels;       // by heap number
  uint32_t leafCount() const { return points.leafCount; }
};

// The paper's nodes and the surfels of a float-encoded hierarchy; selection fields cleared.
EnvHierarchy makeEnvHierarchy(PointHierarchy points);

}  // namespace lucent
