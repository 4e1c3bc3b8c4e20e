// --method purcell and --method pmfg: their options, declared once, and their entries in the
// method list.
#include <bit>

#include "lucent/methods/photonmap.h"
#include "lucent/pipeline/render_options.h"

namespace lucent {

namespace {

// The photon maps' options, the same for both renderers.
void declarePhotonMapOptions(OptionTable<PhotonMapOptions>& t) {
  using O = PhotonMapOptions;
  t.integer("photons", &O::photons, 0, 1 << 28, "paths",
            "photon paths emitted for the global map");
  t.integer("caustic_photons", &O::causticPhotons, 0, 1 << 28, "paths",
            "photon paths emitted for the caustic map, towards the mirrors and glass (0: no caustic map)");
  t.integer("k", &O::k, 1, 1 << 20, "photons", "photons sought per radiance estimate");
  t.integer("caustic_k", &O::causticK, 0, 1 << 20, "photons",
            "photons sought in the caustic map (0: k)");
  t.real("max_radius", &O::maxRadius, 0, 1e30, "scene units",
         "maximum search radius (0: 0.1 x the scene's bounding-box diagonal)");
  t.choice("map", &O::map,
           std::vector<std::pair<std::string, PhotonMapKind>>{{"sort", PhotonMapKind::Sort},
                                                              {"stencil", PhotonMapKind::Stencil},
                                                              {"hash", PhotonMapKind::Hash},
                                                              {"kdtree", PhotonMapKind::KdTree}},
           "where photons are stored and searched: the sorted, stencil-routed or hashed grid, or the kd-tree");
  t.integer("shells", &O::shells, 0, 1 << 20, "shells",
            "stop each kNN-grid search after this many shells (the progressive estimate; 0: to the end)");
  t.rule("shells", [](const O& o) {
    return o.shells > 0 && o.map == PhotonMapKind::KdTree ? "applies to the grid maps (sort, stencil, hash), not kdtree"
                                                          : "";
  });
  t.integer("photon_bounces", &O::maxPhotonBounces, 1, 255, "bounces",
            "interactions followed per photon path (a photon's bounce count has 8 bits)");
  t.triple("grid_resolution", &O::gridResolution, 1, 1 << 21, "cells",
           "grid cells per axis, XxYxZ (auto: from the photons)");
  t.real("cell_size", &O::cellSize, 0, 1e30, "scene units",
         "cubic grid cells of this side (0: from the photons)");
  t.real("photons_per_cell", &O::photonsPerCell, 0, 1e9, "photons",
         "otherwise, about this many photons per cell of the photons' bounds (0: max(1, k / 16))");
  t.integer("stencil_side", &O::stencilSide, 1, 1024, "photons",
            "m, with m x m photons per stencil-routed cell");
}

OptionTable<PhotonMapOptions> rendererTable(PhotonMapOptions defaults, bool finalGathering) {
  using O = PhotonMapOptions;
  OptionTable<O> t(defaults);
  t.include(&O::common, commonOptionTable(kCameraRaysHelp));
  t.include(&O::shading, shadingPointOptionTable());
  declarePhotonMapOptions(t);
  if (finalGathering) {
    t.integer("gather_rays", &PhotonMapOptions::gatherRays, 0, 1 << 20, "rays",
              "final-gather rays per shading point");
    t.choice("gather_estimate", &PhotonMapOptions::gatherEstimate,
             std::vector<std::pair<std::string, GatherEstimate>>{{"irradiance", GatherEstimate::Irradiance},
                                                                 {"photons", GatherEstimate::Photons}},
             "a gather ray's diffuse hit reads the irradiance precomputed at photons nearest to it (Christensen "
             "1999), or estimates from the photons (k nearest)");
    t.integer("irradiance_stride", &PhotonMapOptions::irradianceStride, 1, 1 << 20,
              "photons", "the irradiance is precomputed at every n-th photon of the global map");
  }
  return t;
}

}  // namespace

const OptionTable<PhotonMapOptions>& purcellOptionTable() {
  static const OptionTable<PhotonMapOptions> table = rendererTable({}, false);
  return table;
}

const OptionTable<PhotonMapOptions>& pmfgOptionTable() {
  static const OptionTable<PhotonMapOptions> table = [] {
    PhotonMapOptions defaults;
    defaults.map = PhotonMapKind::KdTree;
    // Twice Purcell's count: at 4,096 gather rays the global map's error dominates (Cornell box 128 x
    // 128: relMSE 0.00067 -> 0.00035-0.00040 with 256 shadow rays) for a few seconds more.
    defaults.photons = 130000;
    return rendererTable(defaults, true);
  }();
  return table;
}

const Method& purcellMethod() {
  static const DeclaredMethod<PhotonMapOptions> method(
      "purcell", "photon mapping on the GPU (Purcell et al. 2003): grid maps and the kNN-grid estimate, visualized",
      purcellOptionTable(), renderPurcell, true, TransmissionRendered::All);
  return method;
}

const Method& pmfgMethod() {
  static const DeclaredMethod<PhotonMapOptions> method(
      "pmfg", "ray tracing with photon maps and final gathering (Jensen): the second ground truth",
      pmfgOptionTable(), renderPhotonMapFinalGather, true, TransmissionRendered::All);
  return method;
}

}  // namespace lucent
