// The photon-mapping renderers: Purcell et al. 2003's ray tracer that visualizes the photon maps at
// diffuse hits (--method purcell), and the RT/PM/FG ground truth with final gathering (--method pmfg).
// src/methods/photonmap/README.md maps the papers to the code and lists the departures. The options
// are declared in purcellOptionTable and pmfgOptionTable (method.cpp).
#pragma once
#include <array>
#include <cstdint>
#include <string>

#include "lucent/pipeline/method.h"
#include "lucent/pipeline/render_options.h"
#include "lucent/pipeline/render_output.h"
#include "lucent/scene/scene.h"
#include "lucent/trace/visibility.h"

namespace lucent {

// Where photons are stored and searched: the sorted grid (section 2.2.1), the stencil-routed grid
// (2.2.2), the hashed grid (4.4), all three searched by the kNN-grid (2.3), or Jensen's kd-tree.
enum class PhotonMapKind { Sort, Stencil, Hash, KdTree };

// What a final-gather ray's hit on a diffuse surface reads (pmfg).
enum class GatherEstimate : uint32_t {
  Irradiance = 0,  // the precomputed irradiance nearest to it (Christensen 1999; Jensen 2001, 9.3)
  Photons = 1,     // a k-nearest-photon radiance estimate (the brute force)
};

struct PhotonMapOptions {
  uint32_t photons = 65000;         // photon paths emitted for the global map (the paper counts the
                                    // photons stored: CORNELL BOX 65,000)
  uint32_t causticPhotons = 65000;  // photon paths emitted for the caustic map, aimed at the specular
                                    // objects' bounding sphere; 0: no caustic map
  uint32_t k = 50;                  // photons sought per radiance estimate (paper: 32, 64, 500)
  uint32_t causticK = 0;            // for the caustic map; 0: k
  float maxRadius = 0;              // maximum search radius; 0: 0.1 x the scene's bounding-box diagonal
  PhotonMapKind map = PhotonMapKind::Sort;  // purcell's default (the paper's); pmfg's is kdtree
                                            // (Jensen's, the ground truth)
  uint32_t shells = 0;              // kNN-grid: stop after this many shells (the progressive estimate
                                    // of section 3.4); 0: run every search to the end
  int gatherRays = 4096;            // pmfg: final-gather rays per shading point
  // pmfg: what a gather ray's diffuse hit reads: the irradiance precomputed at every
  // irradianceStride-th photon (Christensen 1999), or an estimate from the photons themselves.
  GatherEstimate gatherEstimate = GatherEstimate::Irradiance;
  uint32_t irradianceStride = 1;
  uint32_t maxPhotonBounces = 64;   // interactions followed per photon path
  uint64_t bandSamples = kReusableBandSamples;  // the image renders in bands of rows of at most this
                                                // many camera samples (memory); does not change the image
  // The grids (0: chosen from the photons, see GridOptions in src/methods/photonmap/uniform_grid.h).
  std::array<uint32_t, 3> gridResolution{0, 0, 0};  // cells per axis (paper: 250x1x250, 25x25x50)
  float cellSize = 0;                                // cubic cells of this side
  float photonsPerCell = 0;                          // otherwise: about this many photons per cell of the
                                                     // bounds; 0: max(1, k / 16) (measured on the Cornell box)
  uint32_t stencilSide = 16;                         // m: m x m photons per stencil-routed cell
  CommonOptions common;
  ShadingPointOptions shading;
};

// purcell's options and pmfg's (with gather_rays, and the kd-tree by default).
const OptionTable<PhotonMapOptions>& purcellOptionTable();
const OptionTable<PhotonMapOptions>& pmfgOptionTable();
const Method& purcellMethod();
const Method& pmfgMethod();

// Section 3: per pixel, camera rays through mirrors and glass (deterministic splitting), and at
// every diffuse or glossy hit direct light by `lightSamples` shadow rays plus the radiance
// estimates of the global map (indirect photons only) and of the caustic map.
// Both throw OptionError for options outside their declared ranges.
RenderOutput renderPurcell(const Scene& scene, const Visibility& visibility, const PhotonMapOptions& options,
                           const RenderControl& control = {});

// Jensen's RT/PM/FG: as renderPurcell, but indirect light at the first diffuse or glossy hit comes
// from `gatherRays` final-gather rays whose hits use the global map's estimate (all photons).
RenderOutput renderPhotonMapFinalGather(const Scene& scene, const Visibility& visibility,
                                        const PhotonMapOptions& options, const RenderControl& control = {});

}  // namespace lucent
