// --method particles: the particle-space method's options, declared once, and its entry in the
// method list.
#include "lucent/methods/particles.h"
#include "lucent/pipeline/render_options.h"
#include "lucent/techniques/points/point_hierarchy.h"

namespace lucent {

const OptionTable<ParticleOptions>& particleOptionTable() {
  static const OptionTable<ParticleOptions> table = [] {
    using O = ParticleOptions;
    OptionTable<O> t;
    t.include(&O::common, commonOptionTable(kCameraRaysHelp));
    t.include(&O::shading, shadingPointOptionTable());
    t.integer("area_particles", &O::areaParticles, 16, 1 << 24, "positions",
              "places on the surfaces that carry area particles, one per side (the paper: 50,000 CBOX, 150,000 SPONZA)");
    t.choice("sides", &O::sides,
             std::vector<std::pair<std::string, ParticleSides>>{{"both", ParticleSides::Both},
                                                                {"front", ParticleSides::Front}},
             "a particle on each side of a surface, or on the side its winding faces only (the paper's one-sided surfaces)");
    t.choice("particle_area", &O::particleArea,
             std::vector<std::pair<std::string, ParticleArea>>{{"catchment", ParticleArea::Catchment},
                                                               {"uniform", ParticleArea::Uniform}},
             "a particle's area: the surface nearest to it, measured, or the mean area per position (the paper's)");
    t.integer("area_samples", &O::areaSamples, 1, 4096, "points",
              "surface points per position that measure the particles' catchments");
    t.choice("point_sampling", &O::pointSampling,
             std::vector<std::pair<std::string, PointSampling>>{{"best-candidate", PointSampling::BestCandidate},
                                                                {"low-discrepancy", PointSampling::LowDiscrepancy}},
             "area particles by best-candidate sampling or by a scrambled Sobol sequence, both uniform by area");
    t.integer("scatter_links", &O::scatterLinks, 1, 64, "per side",
              "n_s: each particle scatters along n_s x n_s links (the paper: 4)");
    t.integer("gather_links", &O::gatherLinks, 1, 64, "per side",
              "n_s: each particle gathers along n_s x n_s links (the paper: 16)");
    t.integer("bounces", &O::bounces, 0, 1000, "bounces",
              "n_b: scattering bounces; the image holds n_b + 1 indirect bounces (the paper: 8 for CBOX, SPONZA)");
    t.real("link_radius", &O::linkRadius, 0.1, 100, "spacings",
           "a link's particle lies within this distance of the link's hit, in mean particle spacings");
    t.real("tessellation", &O::tessellation, 0.1, 1e6, "spacings",
           "subtriangles' longest edge (radiance particles' spacing), in mean area-particle spacings");
    t.real("list_radius", &O::listRadius, 0.1, 100, "spacings",
           "estimation lists hold the area particles within this radius, in mean particle spacings");
    t.real("list_angle", &O::listAngle, 0, 90, "degrees",
           "estimation lists hold particles whose normals are at most this far from the radiance particle's");
    t.choice("geometry", &O::geometry,
             std::vector<std::pair<std::string, ParticleGeometry>>{{"frame", ParticleGeometry::Frame},
                                                                   {"all", ParticleGeometry::All}},
             "build gathering links and estimation lists where the frame needs them, or everywhere (the paper's "
             "geometry stage, for any view); the image is the same");
    t.integer("supersample", &O::supersample, 0, 16, "per side",
              "adaptive supersampling (4.3.3): pixels that differ from a neighbour get n x n samples; 0: off (the "
              "paper's rate is 9 to 16: 3 or 4)");
    t.rule("supersample", [](const O& o) {
      return o.supersample > 0 && o.common.spp != 1 ? "needs --spp 1 (it supersamples a single-sample frame)" : "";
    });
    t.real("alias_contrast", &O::aliasContrast, 0, 1, "",
           "adaptive supersampling flags a pixel whose luminance differs from a neighbour's by this contrast");
    t.integer("emission_samples", &O::emissionSamples, 1, 1 << 16, "rays",
              "shadow rays per particle for area lights and the environment (point and directional lights: one)");
    return t;
  }();
  return table;
}

const Method& particlesMethod() {
  static const DeclaredMethod<ParticleOptions> method(
      "particles",
      "diffuse GI in particle spaces (Chang, Park and Ihm 2015): area particles and links, radiance particles "
      "and estimation lists",
      particleOptionTable(), renderParticles, false, TransmissionRendered::InPart);
  return method;
}

}  // namespace lucent
