// The unbiased reference path tracer (--method pt): next-event estimation combined with BSDF
// sampling by multiple importance sampling, Russian roulette, box-filtered pixels. Its options are
// declared in pathTraceOptionTable (method.cpp).
#pragma once
#include <cstdint>

#include "lucent/core/sampler_kind.h"
#include "lucent/pipeline/method.h"
#include "lucent/pipeline/render_options.h"
#include "lucent/pipeline/render_output.h"
#include "lucent/scene/scene.h"
#include "lucent/trace/visibility.h"

namespace lucent {

// How light is found: both strategies combined by MIS (the default), or one of them alone, for
// validating the other two (all three converge to the same image).
enum class PathStrategy { Mis, LightSampling, BsdfSampling };

// How Russian roulette chooses the paths that go on: by what each is expected to add to its
// pixel's relative error (the default; src/methods/pathtrace/contribution_roulette.h), or by its
// throughput alone.
enum class RouletteKind { Contribution, Throughput };

// How next-event estimation chooses a light: learnt from contribution roulette's pilot, per kind of
// light (the default; src/methods/pathtrace/contribution_roulette.h), or by the lights' power.
enum class LightChoiceKind { Learned, Power };

struct PathTraceOptions {
  int maxDepth = 1024;         // path length in bounces: 1 is direct light, 2 adds one indirect bounce;
                               // high enough by default that Russian roulette, not the cut, ends paths
  int rouletteDepth = 3;       // Russian roulette from this bounce on
  RouletteKind roulette = RouletteKind::Contribution;
  LightChoiceKind lightChoice = LightChoiceKind::Learned;
  double timeBudget = 0;       // seconds; 0 for none. At least one sample per pixel is taken
  // The relMSE against the converged image to stop at, estimated from the image (error_target.h),
  // with samples spent where the pixels' estimated errors are largest; 0 for none.
  double targetError = 0;
  int tileSize = 16;           // pixels; does not change the image
  bool variance = false;       // add each pixel mean's variance (variance.R, .G, .B), from 2 spp on
  bool paths = false;          // add the light split by path as layers (PathParts, pathLayers)
  PathStrategy strategy = PathStrategy::Mis;
  // Every camera ray through its pixel's centre instead of uniformly over the pixel: the reference
  // for renderers that sample pixel centres (purcell, pmfg and micro at one sample per pixel), whose
  // images are point samples of the image, not its pixels' averages.
  bool pixelCentres = false;
  // Camera rays are started and Lambertian hits shaded many at a time in vectorized loops
  // (CameraLanes, SurfaceLanes), other hits one by one. False runs the same loops one path at a
  // time, and draws each path's Sobol numbers by itself, for tests that the lanes change nothing.
  bool laneShading = true;
  // An Owen-scrambled Sobol sequence padded per bounce and purpose, each light point stratified with
  // the direction its path arrived along (lower error at equal samples), or independent random
  // numbers for validation (include/lucent/core/path_sampler.h).
  SamplerKind sampler = SamplerKind::Sobol;
  CommonOptions common{.spp = 64};  // spp: the most any pixel takes with a time budget or an error target
};

const OptionTable<PathTraceOptions>& pathTraceOptionTable();
const Method& pathTraceMethod();

// Throws OptionError for options outside their declared ranges.
RenderOutput renderPathTraced(const Scene& scene, const Visibility& visibility, const PathTraceOptions& options,
                              const RenderControl& control = {});

}  // namespace lucent
