// --method micro: micro-rendering's options, declared once, and its entry in the method list.
#include <bit>

#include "lucent/methods/microrender.h"
#include "lucent/pipeline/render_options.h"
#include "lucent/techniques/microbuffers/micro_buffer.h"

namespace lucent {

const OptionTable<MicroRenderOptions>& microOptionTable() {
  static const OptionTable<MicroRenderOptions> table = [] {
    using O = MicroRenderOptions;
    OptionTable<O> t;
    t.include(&O::common, commonOptionTable(kCameraRaysHelp));
    t.include(&O::shading, shadingPointOptionTable());
    t.choice("lighting", &O::lighting,
             std::vector<std::pair<std::string, PointLighting>>{{"direct", PointLighting::Direct},
                                                                {"vpl", PointLighting::Vpl},
                                                                {"radiosity", PointLighting::Radiosity},
                                                                {"photons", PointLighting::Photons}},
             "how the points are lit: direct light (one bounce), virtual point lights, radiosity, photons");
    t.integer("points", &O::points, 0, kMaxMicroRenderPoints, "points",
              "leaves of the hierarchy, a power of two (0: from the scene's area and the image's footprint)");
    t.rule("points", [](const O& o) {
      return o.points == 0 || (std::has_single_bit(o.points) && o.points >= 2)
                 ? ""
                 : "must be a power of two of at least 2 (the hierarchy is a complete binary tree), or 0";
    });
    t.real("point_spacing", &O::pointSpacing, 0.01, 1e6, "pixels",
           "for the default point count: the points' mean spacing in pixels of the camera's footprint");
    t.integer("buffer_size", &O::bufferSide, kMinMicroBufferSide, kMaxMicroBufferSide,
              "pixels", "micro-buffer side");
    t.choice("mapping", &O::mapping,
             std::vector<std::pair<std::string, MappingKind>>{{"warped", MappingKind::Warped},
                                                              {"nusselt", MappingKind::Nusselt},
                                                              {"paraboloid", MappingKind::Paraboloid}},
             "micro-buffer mapping: warped by the BRDF (importance warping), Nusselt's, or the paraboloid "
             "projection");
    t.integer("table_size", &O::tableSize, 4, 256, "cells",
              "cells per side of the tabulated BRDF slice (warped mapping)");
    t.flag("ray_casting", &O::rayCasting,
           "ray casting after the traversal (without: holes, as the paper's Fig. 11)");
    t.integer("splat_reach", &O::splatReach, 1, kMaxSplatReach, "pixel spacings",
              "interior nodes are splatted up to this wide (1: into 3 x 3 pixels, 2: 5 x 5)");
    t.choice("node_radiance", &O::nodeRadiance,
             std::vector<std::pair<std::string, NodeRadianceKind>>{{"isotropic", NodeRadianceKind::Isotropic},
                                                                   {"directional", NodeRadianceKind::Directional}},
             "what interior nodes send: their leaves' mean (isotropic, the paper's) or by direction");
    t.integer("upsampling", &O::upsampling, 1, 16, "",
              "gather at 1 / N of the pixels, N = 1, 4 or 16, and upsample bilaterally");
    t.rule("upsampling", [](const O& o) {
      return o.upsampling == 1 || o.upsampling == 4 || o.upsampling == 16 ? "" : "must be 1, 4 or 16";
    });
    t.choice("encoding", &O::encoding,
             std::vector<std::pair<std::string, NodeEncoding>>{{"float", NodeEncoding::Float},
                                                               {"packed", NodeEncoding::Packed}},
             "float nodes, or packed (the paper's 128-bit nodes and half-float radiance)");
    t.integer("point_light_samples", &O::pointLightSamples, 0, 1 << 16, "rays",
              "shadow rays per point of the hierarchy");
    t.integer("vpls", &O::vpls, 1, 1 << 20, "paths",
              "light paths traced for virtual point lights (lighting vpl)");
    t.integer("radiosity_level", &O::radiosityLevel, 1, 22, "",
              "the tree level gathered at (lighting radiosity)");
    t.integer("bounces", &O::bounces, 0, 64, "iterations",
              "Jacobi iterations (lighting radiosity)");
    t.integer("photons", &O::photons, 1, 1 << 28, "paths",
              "photon paths emitted (lighting photons)");
    t.integer("k", &O::k, 1, 1 << 20, "photons",
              "photons per radiance estimate (lighting photons)");
    return t;
  }();
  return table;
}

const Method& microMethod() {
  static const DeclaredMethod<MicroRenderOptions> method(
      "micro", "micro-rendering (Ritschel et al. 2009): final gathering by rasterizing a point hierarchy",
      microOptionTable(), renderMicro, false, TransmissionRendered::InPart);
  return method;
}

}  // namespace lucent
