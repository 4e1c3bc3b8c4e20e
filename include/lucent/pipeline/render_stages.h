// The steps every method's render shares, from the control it is given (render_control.h): the
// part it renders, its prologue, its film, its camera paths' settings, and the loop over bands of
// rows with stop requests and checkpoints between them. For the methods; not installed.
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

// The film a render starts from: empty, or a copy of control.resume, which must be a film of this
// part with this layout (std::invalid_argument otherwise); with features, what its pixels show
// (tracePixelSurfaces) and the scene's material names.
Film startFilm(const RenderControl& control, const Scene& scene, const Visibility& visibility, const RenderPart& part,
               Film::Sums sums, FilmLayers layers);

// The camera paths of a part, following mirrors and glass up to maxSpecularDepth bounces.
EyePathSettings eyePathSettings(const CommonOptions& common, int maxSpecularDepth, const RenderPart& part);

// A band of the part's camera samples into the film: its shading points' light, and its pixels
// marked as having taken all the part's samples.
void addBand(Film& film, const EyePaths& band, const PointRadiance& light, int imageWidth, const RenderPart& part);

// The image of a method that shades every camera sample of its part at once: a film (PerPart sums)
// started as startFilm does, the shading points' light added, every pixel's samples taken; sets
// out's image, film and sppDone, and times stage "image".
void shadeImage(RenderOutput& out, const RenderControl& control, const Scene& scene, const Visibility& visibility,
                const RenderPart& part, const EyePaths& eye, const PointRadiance& light, FilmLayers layers);

// Whether every pixel of the part has all its samples.
bool filmComplete(const Film& film, const RenderPart& part);

// Calls control.checkpoint when control.checkpointSeconds have passed since the last call (or the
// start) and a checkpoint is wanted.
class CheckpointClock {
 public:
  explicit CheckpointClock(const RenderControl& control) : control_(control) {}
  void reached(const Film& film);

 private:
  const RenderControl& control_;
  Stopwatch sinceLast_;
};

// Bands of rows of a region for the methods that render band by band, sized by the work: at most
// `maxSamples` camera samples each (memory), and, once the time per row is known, about
// `targetSeconds` of work, so that a stop request or a checkpoint waits for little. Bands never
// change the image.
class RowBands {
 public:
  RowBands(const RenderPart& part, uint64_t maxSamples, double targetSeconds);
  // The next band [first, second) of rows from `row` on, after the last band took `seconds`.
  std::pair<int, int> next(int row);
  void finished(int rows, double seconds);

 private:
  RenderPart part_;
  uint64_t maxRows_;
  double targetSeconds_, secondsPerRow_ = 0;
};

// The band loop of the methods that shade a band of rows at once: the part's rows in bands of at
// most `maxSamples` camera samples (and about `targetSeconds` of work each, where that is above 0;
// RowBands), from the first row the film does not hold in full (a resumed render). Each band goes
// to `renderBand` with its index (0, 1, ... from that row) and a progress callback taking the
// fraction of the band done, reported to control.progress mapped into [progressFrom, progressTo].
// Between bands: stop requests, and checkpoints of the film. Returns false when a stop ended the
// loop; a band that a stop interrupts (RenderStopped) is dropped whole.
struct BandLoop {
  uint64_t maxSamples = kReusableBandSamples;
  double targetSeconds = 0;
  double progressFrom = 0, progressTo = 1;
};
using BandRenderer =
    std::function<void(const PixelRect& band, size_t index, const std::function<void(double)>& progress)>;
bool renderRowBands(const RenderControl& control, const RenderPart& part, const BandLoop& loop, const Film& film,
                    const BandRenderer& renderBand);

}  // namespace lucent
