// The steps every method's render shares, from the control it is given (render_control.h): the
// part it renders, its prologue, its camera paths' settings and how a band of them reaches the
// film. The loop itself is the render driver's (render_driver.h). For the methods; not installed.
#pragma once
#include <cstdint>
#include <functional>
#include <string_view>
#include <utility>

#include "lucent/core/stats.h"
#include "lucent/pipeline/film.h"
#include "lucent/pipeline/options.h"
#include "lucent/pipeline/pixel_rect.h"
#include "lucent/pipeline/render_control.h"
#include "lucent/pipeline/render_options.h"
#include "lucent/pipeline/render_output.h"
#include "lucent/pipeline/shading_points.h"
#include "lucent/scene/scene.h"

namespace lucent {

// A control's part made concrete for a scene and a method's spp: throws std::invalid_argument
// naming --crop or --samples when it is not inside the image or the samples.
struct RenderPart {
  PixelRect region;
  int sampleBegin = 0, sampleEnd = 0;
  int samples() const { return sampleEnd - sampleBegin; }
};
RenderPart resolvePart(const RenderControl& control, const Scene& scene, int spp);

// Refuses a resume or checkpoints (std::invalid_argument) for a method that renders its image at
// once, with no state between stages to save: `atOnce` says so ("--method micro gathers the whole
// image at once").
void refuseResume(const RenderControl& control, std::string_view atOnce);

// The start every method's render shares: its options checked against their declarations, a
// resume or checkpoints refused where the method renders at once (`atOnce` non-empty, as for
// refuseResume), and the part the control asks for.
template <class Options>
RenderPart beginRender(const OptionTable<Options>& table, const Options& options, const RenderControl& control,
                       const Scene& scene, std::string_view atOnce = {}) {
  table.validate(options);
  if (!atOnce.empty()) refuseResume(control, atOnce);
  return resolvePart(control, scene, options.common.spp);
}

// The camera paths of a part, following mirrors and glass up to maxSpecularDepth bounces.
EyePathSettings eyePathSettings(const CommonOptions& common, int maxSpecularDepth, const RenderPart& part);

// A band of the part's camera samples into the film: its shading points' light, and its pixels
// marked as having taken all the part's samples.
void addBand(Film& film, const EyePaths& band, const PointRadiance& light, int imageWidth, const RenderPart& part);

}  // namespace lucent
