// Primary and secondary visible points and the traversals that decide which points need a
// micro-buffer of their own (the environment-lighting PBGI paper, 3.3, 3.4, Fig. 3, section 4).
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "lucent/scene/camera.h"
#include "lucent/scene/scene.h"
#include "lucent/trace/visibility.h"
#include "methods/envpbgi/env_points.h"

namespace lucent {

// The camera's depth buffer (the paper rasterizes it with OpenGL): per pixel the distance to the
// first hit of the ray through the pixel's centre, infinite for a miss.
struct CameraDepth {
  int width = 0, height = 0;
  std::vector<float> depth;  // row-major
};
// Camera rays in packets of 16, one per pixel through its centre (Embree: the paper's OpenGL pass).
CameraDepth traceCameraDepth(const Scene& scene, const Visibility& visibility);

struct PrimarySelection {
  float maxSolidAngle = 0;  // Omega_max, steradians
  float maxConeAngle = 0;   // radians
  // A departure (README): the largest thickness of a primary point's leaves about its plane
  // (MicroHierarchy::thickness), in units of its radius. A node holding two parallel surfaces apart
  // (a floor inside a box and the ground outside) has a small cone but its surfel lies between the
  // surfaces, where its micro-buffer sees what neither does.
  float maxThickness = 0.25f;
  std::span<const float> thickness;  // per node
};

// 3.4, 4 "Select Primary Visible Points": the cut of the hierarchy where a node's solid angle from
// the eye (pi r^2 / d^2 of its sphere, QSplat's measure), its normal-cone angle and its thickness all
// first fall below their thresholds on the way down from the root (leaves end every path), kept where the
// depth buffer shows it: where a pixel of its sphere's image (up to 8 x 8 of them, evenly spread)
// sees a surface point within the sphere and within the slab about its plane that holds its leaves
// (MicroHierarchy::thickness), both grown by the spacing of those pixels at that depth. One
// work item per node, level by level from the root, so that a node's "an ancestor passed" is read
// from its parent (the paper checks a node's children from the node; the solid angle is not
// monotone down the tree, so only this keeps the set a cut). Sets kPrimary; returns the primary
// points in index order.
std::vector<uint32_t> selectPrimaryPoints(EnvHierarchy& h, const Camera& camera, const CameraDepth& depth,
                                          const PrimarySelection& selection);

// 4 "Select Secondary Visible Points": every node that a primary point's micro-buffer shows
// (texels: packed depth | node words, kEmptyMicroPixel for none) gets kSecondary.
void markSecondaryPoints(EnvHierarchy& h, std::span<const uint32_t> texels);

struct SelectionCounts {
  uint64_t primary = 0, secondary = 0;
  uint64_t afterUpward = 0;    // secondary points whose direct light does not follow from their children
  uint64_t afterDownward = 0;  // ... nor from a primary ancestor (the paper's Fig. 5 and Table 1)
  uint64_t ownBuffers = 0;     // of those, the ones that are not primary points themselves
};

// 3.3, 3.4, Fig. 3, 4 "Select Direct Illumination Computation Points". Upward: one work item per
// leaf climbs through the parents; a per-node arrival counter lets the first child's work item stop
// and the second carry on (the paper's atomic counter), so a node is decided once both children
// are: covered = source (a secondary point; also a primary one with primarySources) or both
// children covered; a secondary point with both children covered is derivable (kDerivable).
// Downward: one work item per primary point marks the secondary points below it (kUnderPrimary).
// The rest of the secondary points that are not primary points get kOwnBuffer.
SelectionCounts selectDirectLightPoints(EnvHierarchy& h, std::span<const uint32_t> primary, bool primarySources);

}  // namespace lucent
