// The variants of the techniques that methods' options choose among, apart from the techniques
// themselves, so that the methods' options (lucent/methods/*.h) name them without the techniques'
// headers.
#pragma once
#include <cstdint>

namespace lucent {

// How a micro-buffer maps directions of the hemisphere to its pixels
// (techniques/microbuffers/hemisphere_mapping.h).
enum class MappingKind : uint32_t { Nusselt = 0, Warped = 1, Paraboloid = 2 };

// How points are placed on the surfaces (techniques/points/point_hierarchy.h).
enum class PointSampling : uint32_t {
  BestCandidate = 0,   // Ritschel et al. 2009, 2.1: each point the farthest of its candidates
  LowDiscrepancy = 1,  // the environment-lighting PBGI paper's: a scrambled Sobol sequence by area
};

// A point hierarchy's nodes as floats, or as the micro-rendering paper's 128-bit records.
enum class NodeEncoding : uint32_t { Float = 0, Packed = 1 };

// What a node sends: its leaves' area-weighted mean every way (the paper's nodes), or towards each
// direction its leaves' radiance weighted by the area they show that way (DirectionalRadiance).
enum class NodeRadianceKind { Isotropic, Directional };

}  // namespace lucent
