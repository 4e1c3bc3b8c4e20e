// Diffuse global illumination in particle spaces (Chang, Park and Ihm, Multimedia Tools and
// Applications 74(13), 2015), --method particles: area particles joined by precomputed links
// carry light from the lights by scattering and gathering, radiance particles on a tessellation of
// the triangles take it from their estimation lists, and a Whitted ray tracer interpolates it at
// every diffuse hit. src/methods/particles/README.md maps the paper to the code. The options are
// declared in particleOptionTable (method.cpp).
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

// The paper's surfaces have one side that matters; Lucent's surfaces reflect on both (as the path
// tracer's do), so a position carries a particle for each side by default.
enum class ParticleSides : uint32_t { Both = 0, Front = 1 };

// How a particle's Delta A is set: the area per position (4.3.1: "constant area Delta A"), or the
// area of the surface nearest to it, which is what links and lookups hand it.
enum class ParticleArea : uint32_t { Catchment = 0, Uniform = 1 };

// What the geometry stage builds (4.1): everything, as the paper's does, for any view and lights; or
// only what the frame needs, gathering links at the used area particles and lists at the found
// radiance particles, built when the frame has found them. The image is the same.
enum class ParticleGeometry : uint32_t { Frame = 0, All = 1 };

struct ParticleOptions {
  uint32_t areaParticles = 50000;  // positions on the surfaces (the paper: 50,000 CBOX, 150,000 SPONZA)
  ParticleSides sides = ParticleSides::Both;
  ParticleArea particleArea = ParticleArea::Catchment;
  int areaSamples = 32;     // surface points per position that measure the catchments
  PointSampling pointSampling = PointSampling::BestCandidate;
  int scatterLinks = 4;     // n_s of the scattering links (the paper: 4 x 4)
  int gatherLinks = 16;     // n_s of the gathering links (the paper: 16 x 16)
  int bounces = 8;          // n_b, scattering bounces (the paper: 8 for CBOX and SPONZA)
  float linkRadius = 2;     // a link's particle is at most this far from its hit, in particle spacings
  float tessellation = 3;   // longest subtriangle edge, in particle spacings
  float listRadius = 4;     // estimation list radius, in particle spacings
  float listAngle = 37;     // degrees: a list's particles' normals are at most this far from its own
  int emissionSamples = 16; // shadow rays per particle for area lights and the environment
  ParticleGeometry geometry = ParticleGeometry::Frame;
  int supersample = 0;        // adaptive supersampling: flagged pixels get n x n samples (0: off)
  float aliasContrast = 0.1f; // luminance contrast that flags a pixel
  CommonOptions common;
  ShadingPointOptions shading;
};

const OptionTable<ParticleOptions>& particleOptionTable();
const Method& particlesMethod();

// Throws OptionError for options outside their declared ranges, MemoryLimitError when the links or
// lists would not fit.
RenderOutput renderParticles(const Scene& scene, const Visibility& visibility, const ParticleOptions& options,
                             const RenderControl& control = {});

}  // namespace lucent
