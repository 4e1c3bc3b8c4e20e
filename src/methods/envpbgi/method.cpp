// --method envpbgi: the environment-lighting PBGI method's options, declared once, and its entry in
// the method list.
#include <bit>

#include "lucent/methods/envpbgi.h"
#include "lucent/pipeline/render_options.h"
#include "lucent/techniques/microbuffers/micro_buffer.h"

namespace lucent {

const OptionTable<EnvPbgiOptions>& envPbgiOptionTable() {
  static const OptionTable<EnvPbgiOptions> table = [] {
    using O = EnvPbgiOptions;
    OptionTable<O> t;
    t.include(&O::common, commonOptionTable(kCameraRaysHelp));
    declareMaxSpecularDepth(t, &O::maxSpecularDepth);
    declareDumpDirectory(t, &O::dumpDirectory);
    t.integer("points", &O::points, 2, kMaxMicroRenderPoints, "points",
              "leaves of the hierarchy, a power of two (the paper: 500,000)");
    t.rule("points", [](const O& o) {
      return std::has_single_bit(o.points) ? "" : "must be a power of two (the hierarchy is a complete binary tree)";
    });
    t.choice("point_sampling", &O::pointSampling,
             std::vector<std::pair<std::string, PointSampling>>{{"low-discrepancy", PointSampling::LowDiscrepancy},
                                                                {"best-candidate", PointSampling::BestCandidate}},
             "points by a scrambled Sobol sequence (the paper's) or by best-candidate sampling (Ritschel's)");
    t.choice("mapping", &O::mapping,
             std::vector<std::pair<std::string, MappingKind>>{{"paraboloid", MappingKind::Paraboloid},
                                                              {"nusselt", MappingKind::Nusselt}},
             "micro-buffer projection: paraboloid (the paper's) or Nusselt's");
    t.integer("primary_buffer_size", &O::primaryBufferSide, kMinMicroBufferSide,
              kMaxMicroBufferSide, "pixels", "side of the primary points' micro-buffers (and the brute force's at pixels)");
    t.integer("secondary_buffer_size", &O::secondaryBufferSide, 4, kMaxMicroBufferSide,
              "pixels", "side of the secondary points' micro-buffers (and the brute force's at leaves)");
    t.integer("splat_reach", &O::splatReach, 1, kMaxSplatReach, "texel spacings",
              "interior nodes are splatted up to this wide (1: into 3 x 3 texels, 2: 5 x 5)");
    t.real("primary_pixels", &O::primaryPixels, 1e-3, 1e9, "pixels",
           "a primary point's largest solid angle from the eye, in pixels at the image's centre");
    t.real("primary_cone_angle", &O::primaryConeAngle, 0.01, 180, "degrees",
           "a primary point's largest normal-cone angle");
    t.flag("primary_sources", &O::primarySources,
           "the upward traversal counts primary points as sources of direct light (fewer micro-buffers)");
    t.real("cache_radius_scale", &O::cacheRadiusScale, 1e-3, 1e3, "",
           "a radiance cache's effective radius in units of its point's radius");
    t.real("cache_max_angle", &O::cacheMaxAngle, 0.01, 90, "degrees",
           "caches are used by receivers whose normal is at most this far from theirs");
    t.integer("tile_size", &O::tileSize, 1, 4096, "pixels",
              "side of the screen-space grid's tiles");
    t.choice("direct_light", &O::directLight,
             std::vector<std::pair<std::string, PointDirectLight>>{{"selected", PointDirectLight::Selected},
                                                                   {"every-leaf", PointDirectLight::EveryLeaf}},
             "direct light at the paper's selected points, or by a micro-buffer at every leaf (Fig. 8's brute force)");
    t.choice("pixel_irradiance", &O::pixelIrradiance,
             std::vector<std::pair<std::string, PixelIrradiance>>{{"caches", PixelIrradiance::Caches},
                                                                  {"every-pixel", PixelIrradiance::EveryPixel}},
             "pixels read the radiance caches, or gather by a micro-buffer each (Fig. 8's brute force)");
    t.rule("pixel_irradiance", [](const O& o) {
      return o.pixelIrradiance == PixelIrradiance::EveryPixel && o.directLight != PointDirectLight::EveryLeaf
                 ? "every-pixel needs --direct-light every-leaf (a pixel's buffer shows nodes the selection did not light)"
                 : "";
    });
    return t;
  }();
  return table;
}

const Method& envPbgiMethod() {
  static const DeclaredMethod<EnvPbgiOptions> method(
      "envpbgi",
      "point-based GI under environment lighting (AMD; Harada 2014): primary and secondary visible points, "
      "propagation, radiance caches",
      envPbgiOptionTable(), renderEnvPbgi, false, TransmissionRendered::InPart);
  return method;
}

}  // namespace lucent
