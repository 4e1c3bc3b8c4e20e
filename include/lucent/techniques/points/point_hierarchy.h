// The hierarchical point-based representation of the scene (Ritschel et al. 2009, 2.1 and 3.1),
// shared by micro-rendering and point-based GI under environment lighting: points on the triangles
// by best-candidate sampling, a complete binary tree over them by recursive median split, and per
// node a bounding sphere, a cone of normals and an albedo, in full float or in the paper's 128 bits.
// src/techniques/points/README.md maps the paper to the functions.
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "lucent/core/math.h"
#include "lucent/core/stats.h"
#include "lucent/scene/scene.h"
#include "lucent/techniques/points/node_tree.h"
#include "lucent/techniques/points/point_nodes.h"
#include "lucent/techniques/technique_kinds.h"

namespace lucent {

// A point on the scene's surface, as triangle and barycentrics (2.1), so that its position and
// normal follow deforming geometry.
struct PointSample {
  uint32_t triangle = 0;
  float b1 = 0, b2 = 0;  // b0 = 1 - b1 - b2
};
static_assert(sizeof(PointSample) == 12, "PointSample is a fixed-size record shared with GPU backends");

// The sample's position against the scene's current vertex positions (as surfaceAt computes it).
inline Vec3 pointPosition(const Scene& scene, const PointSample& s) {
  const uint32_t* v = &scene.indices[3 * s.triangle];
  return barycentric(scene.positions[v[0]], scene.positions[v[1]], scene.positions[v[2]], s.b1, s.b2);
}

struct PointSamplingOptions {
  PointSampling method = PointSampling::BestCandidate;
  uint32_t candidates = 8;  // best-candidate candidates per point (1: plain uniform-by-area sampling)
  uint64_t seed = 0;
  // Tile edge in units of the mean point spacing of the level being added; tiles of one colour are
  // processed in parallel (see samplePoints). Larger: fewer tiles, longer neighbour lists.
  float tileScale = 2.0f;
};

// `count` points on the scene's triangles, uniform by area, spread by best-candidate sampling
// (Mitchell 1991): each point is, of its candidates, the one farthest from the points already placed;
// or (options.method LowDiscrepancy) point i at the i-th point of an Owen-scrambled Sobol sequence:
// the first coordinate picks the triangle by area, the other two its barycentrics (stage
// "point_sampling", counter "points").
// Every triangle is eligible, emitters and specular surfaces included; the per-triangle counts are
// area-proportional in expectation. Any count works (a power of two for a hierarchy). Deterministic
// for a seed whatever the thread count. Stage "point_sampling"; counters "points",
// "point_candidates", "points_with_few_candidates" (fewer than half of `candidates`: points on
// pieces of triangles too small for a full share). Throws std::invalid_argument for a count of 0 or
// above 2^26, bad options, or a scene without area.
std::vector<PointSample> samplePoints(const Scene& scene, uint32_t count, const PointSamplingOptions& options = {},
                                      RenderStats* stats = nullptr);

// The order of the points that defines the tree (2.1): recursive split at the median along the axis
// of largest extent. Returns, for each tree position j (leaf n + j), the index of its input point.
// The size must be a power of two. Ties are broken by input index, so the order is unique.
std::vector<uint32_t> medianSplitOrder(std::span<const Vec3> positions);

struct PointHierarchyOptions {
  uint32_t pointCount = 1u << 16;  // n, a power of two
  PointSamplingOptions sampling;
  // Leaf disc area in units of the surface area each point stands for (total area / n): radius
  // sqrt(discAreaScale * area / (n pi)). 1 would preserve area, but discs at best-candidate positions
  // then leave 19% of the surface uncovered, 2 leave 1.7%, 3 leave 0.13% (Cornell box, README "Disc
  // radius"): discs are for visibility and must close the surface. Radiometry uses nodeAreas, which
  // does not depend on this.
  float discAreaScale = 3.0f;
  // Packed: the paper's 128-bit nodes in packedNodes (the float nodes are kept as the reference).
  NodeEncoding encoding = NodeEncoding::Packed;
};

struct PointHierarchy {
  uint32_t leafCount = 0;  // n
  NodeEncoding encoding = NodeEncoding::Packed;
  float discAreaScale = 3.0f;
  float restPointArea = 0;               // surface area per point at build time: total area / n
  std::vector<PointSample> points;       // tree order: point j is leaf node n + j
  std::vector<float> restTriangleAreas;  // per triangle at build time, for the radius under deformation
  // Per node, indexed by heap number (node_tree.h): 2n entries, entry 0 unused.
  std::vector<FloatNode> floatNodes;
  std::vector<float> nodeAreas;          // surface area the node stands for: sum of its leaves'
  std::vector<PackedNode> packedNodes;   // encoding == Packed only
  NodeQuantization quantization;         // of packedNodes

  uint32_t nodeCount() const { return 2 * leafCount; }  // array size (node 0 unused)
  FloatNodeReader floatReader() const { return {floatNodes.data()}; }
  PackedNodeReader packedReader() const { return {packedNodes.data(), quantization}; }
  // The node as the selected encoding stores it, decoded.
  FloatNode node(uint32_t i) const {
    return encoding == NodeEncoding::Packed ? decodeNode(packedNodes[i], quantization) : floatNodes[i];
  }
};

// Samples options.pointCount points and builds the hierarchy over them. Stages: those of
// samplePoints, then "median_split", then those of refitPointHierarchy; counter
// "points_on_emitters".
PointHierarchy buildPointHierarchy(const Scene& scene, const PointHierarchyOptions& options,
                                   RenderStats* stats = nullptr);
// The same over given points (any order; a power-of-two count): the median split, the rest state
// (triangle areas, area per point) from `scene`, then the node data.
PointHierarchy buildPointHierarchy(const Scene& scene, std::vector<PointSample> points,
                                   const PointHierarchyOptions& options, RenderStats* stats = nullptr);

// Recomputes all node data, in O(n), for the scene's current vertex positions (2.1, "Deforming and
// moving geometry"): the tree and the points' triangles and barycentrics stay; leaves get their new
// position and face normal, their area scaled by the triangle's area over its rest area and their
// radius with it ("we scale the points' radii to compensate for the varying point densities"); then
// interior nodes level by level, bottom-up. Stages "leaf_nodes", "interior_nodes" and, for the
// packed encoding, "packed_nodes".
void refitPointHierarchy(PointHierarchy& hierarchy, const Scene& scene, RenderStats* stats = nullptr);

}  // namespace lucent
