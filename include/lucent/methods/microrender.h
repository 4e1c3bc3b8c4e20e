// Micro-rendering (Ritschel et al. 2009, "Micro-Rendering for Scalable, Parallel Final Gathering"),
// --method micro: final gathering at the camera's diffuse and glossy surface points by rasterizing a
// point hierarchy of the scene into importance-warped micro-buffers. src/methods/microrender/README.md
// maps the paper to the code and lists the departures. The options are declared in
// microOptionTable (method.cpp).
#pragma once
#include <cstdint>
#include <string>

#include "lucent/pipeline/method.h"
#include "lucent/pipeline/render_options.h"
#include "lucent/pipeline/render_output.h"
#include "lucent/scene/scene.h"
#include "lucent/techniques/technique_kinds.h"
#include "lucent/trace/visibility.h"

namespace lucent {

// How the points of the hierarchy get the radiance that gathering sees (paper, section 4).
enum class PointLighting {
  Direct,     // direct light at the points: one indirect bounce
  Vpl,        // direct light plus virtual point lights (instant radiosity): multiple bounces
  Radiosity,  // direct light plus Jacobi gathering at an interior level with push-pull
  Photons,    // the photon map's radiance estimate at the leaves, pulled up
};

struct MicroRenderOptions {
  PointLighting lighting = PointLighting::Direct;
  uint32_t points = 0;             // leaves of the hierarchy, a power of two; 0: defaultPointCount
  float pointSpacing = 4.0f;       // for the default count: mean point spacing in pixels of the camera's footprint
  int bufferSide = 24;             // micro-buffer resolution, 8 to 32 (the paper: 8, 16, 24)
  MappingKind mapping = MappingKind::Warped;
  int tableSize = 32;              // cells per side of the tabulated BRDF slice (warped mapping)
  bool rayCasting = true;          // false: no post-traversal ray casting (the paper's Fig. 11)
  int splatReach = 2;              // interior nodes splatted up to this many pixel spacings wide: 1 or 2 (README)
  NodeRadianceKind nodeRadiance = NodeRadianceKind::Directional;  // what interior nodes send each way (README)
  int upsampling = 1;              // gather at 1/upsampling of the pixels: 1, 4 or 16 (bilateral upsampling)
  // Float nodes, or the paper's 128-bit nodes and half-float radiance. Float by default: on the CPU
  // they gather 5-10% faster (decoding costs more than the memory saved) and no less accurately
  // (README).
  NodeEncoding encoding = NodeEncoding::Float;
  int pointLightSamples = 16;      // shadow rays per point of the hierarchy
  uint32_t vpls = 256;             // Vpl: light paths traced for virtual point lights
  int radiosityLevel = 12;         // Radiosity: the tree level gathered at (4,096 nodes, the paper's)
  int bounces = 2;                 // Radiosity: Jacobi iterations (indirect bounces at the points)
  uint32_t photons = 200000;       // Photons: photon paths emitted
  uint32_t k = 50;                 // Photons: photons per radiance estimate
  CommonOptions common;
  ShadingPointOptions shading;
};

const OptionTable<MicroRenderOptions>& microOptionTable();
const Method& microMethod();

// The point count a scene needs when none is given: leaves spaced about `spacing` pixels of the
// camera's footprint apart at the distance from the eye to the centre of the scene's bounds, over
// the scene's whole surface area, rounded to a power of two in [2^12, 2^22].
uint32_t defaultPointCount(const Scene& scene, float spacing);

// Throws OptionError for options outside their declared ranges.
RenderOutput renderMicro(const Scene& scene, const Visibility& visibility, const MicroRenderOptions& options,
                         const RenderControl& control = {});

}  // namespace lucent
