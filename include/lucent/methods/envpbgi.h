// Point-based global illumination under environment lighting ("A Point-based Global Illumination
// Rendering Pipeline for Environment Lighting", AMD; Harada, GI 2014), --method envpbgi: one-bounce
// indirect light under an environment and a sun with as few micro-buffer rasterizations as
// possible: primary visible points chosen from the point hierarchy for the camera, secondary ones
// from their micro-buffers, the hierarchy walked up and down to find which need their own buffer,
// direct light propagated, and a radiance cache on the primary points interpolated at every pixel.
// src/methods/envpbgi/README.md maps the paper to the code. The options are declared in
// envPbgiOptionTable (method.cpp).
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

// Where direct light at the points comes from: the paper's selection (3.3, 3.4), or Fig. 8's brute
// force, a micro-buffer at every leaf pulled up the hierarchy.
enum class PointDirectLight : uint32_t { Selected = 0, EveryLeaf = 1 };
// What the pixels read: the radiance caches (3.5), or Fig. 8's brute force, a micro-buffer at every
// shading point (needs direct light at every node: EveryLeaf).
enum class PixelIrradiance : uint32_t { Caches = 0, EveryPixel = 1 };

struct EnvPbgiOptions {
  uint32_t points = 1u << 19;  // leaves, a power of two (the paper: 500,000)
  PointSampling pointSampling = PointSampling::LowDiscrepancy;
  MappingKind mapping = MappingKind::Paraboloid;
  int primaryBufferSide = 16;    // the primary points' micro-buffers (and the brute force's at pixels)
  int secondaryBufferSide = 8;   // the secondary points' (and the brute force's at leaves)
  int splatReach = 2;            // interior nodes splatted up to this many texel spacings wide (micro's option)
  float primaryPixels = 640;     // Omega_max in solid angles of a pixel at the image's centre (README)
  float primaryConeAngle = 30;   // degrees
  bool primarySources = false;   // primary points count as sources in the upward traversal (notes A6)
  float cacheRadiusScale = 2;    // a cache's effective radius: this times its point's radius
  float cacheMaxAngle = 20;      // degrees: Ward's weight is clamped to normals this close
  int tileSize = 16;             // pixels per side of the screen-space grid's tiles
  PointDirectLight directLight = PointDirectLight::Selected;
  PixelIrradiance pixelIrradiance = PixelIrradiance::Caches;
  CommonOptions common;
  int maxSpecularDepth = 10;  // mirror and glass bounces followed from the camera
  std::string dumpDirectory;  // where each stage's arrays are dumped (docs/dump-format.md); empty: none
};

const OptionTable<EnvPbgiOptions>& envPbgiOptionTable();
const Method& envPbgiMethod();

// Throws OptionError for options outside their declared ranges, std::invalid_argument for a scene
// with emitting triangles.
RenderOutput renderEnvPbgi(const Scene& scene, const Visibility& visibility, const EnvPbgiOptions& options,
                           const RenderControl& control = {});

}  // namespace lucent
