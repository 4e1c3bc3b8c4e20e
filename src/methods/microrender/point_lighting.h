// Lighting the points of the hierarchy (Ritschel et al. 2009, section 4): the radiance every node
// sends towards gather points, for one or several indirect bounces.
#pragma once
#include "gathering.h"
#include "lucent/methods/microrender.h"
#include "lucent/scene/scene.h"
#include "lucent/trace/visibility.h"

namespace lucent {

// Fills radiance.rgb (2n entries, by node) for options.lighting: the leaves' reflected radiance
// (their diffuse part: the nodes carry one radiance for all directions, 2.2 "Convolution"), and
// interior nodes by pull. Stages "point_lighting" and its parts, counters of rays and lights.
NodeRadiance lightPoints(const Scene& scene, const Visibility& visibility, const PointHierarchy& hierarchy,
                         const GatherContext& gathering, const MicroRenderOptions& options, RenderStats& stats);

}  // namespace lucent
