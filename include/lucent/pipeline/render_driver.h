// The loop every method renders its image in, owned here as pbrt-v4's ImageTileIntegrator owns its
// integrators' loop: the part and the film the render starts from, the work in bands of rows or in
// passes over tiles, stop requests, progress, checkpoints, and the output the render ends with. A
// method supplies its stages and its per-band or per-tile work. For the methods; not installed.
#pragma once
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string_view>

#include "lucent/core/stats.h"
#include "lucent/pipeline/film.h"
#include "lucent/pipeline/render_control.h"
#include "lucent/pipeline/render_output.h"
#include "lucent/pipeline/render_stages.h"
#include "lucent/scene/scene.h"
#include "lucent/trace/visibility.h"

namespace lucent {

// A band loop's settings: bands of at most `maxSamples` camera samples (memory), and about
// `targetSeconds` of work each where that is above 0 (so that a stop request or a checkpoint waits
// for little; bands never change the image); its progress mapped into [progressFrom, progressTo].
struct BandLoop {
  uint64_t maxSamples = kReusableBandSamples;
  double targetSeconds = 0;
  double progressFrom = 0, progressTo = 1;
};
// A band of rows, its index (0, 1, ... from the first row the loop renders) and a progress callback
// taking the fraction of the band done.
using BandRenderer =
    std::function<void(const PixelRect& band, size_t index, const std::function<void(double)>& progress)>;

class RenderDriver {
 public:
  // beginRender's checks first: the options against their declarations, a resume or checkpoints
  // refused where the method renders at once (`atOnce` non-empty), the part.
  template <class Options>
  RenderDriver(const OptionTable<Options>& table, const Options& options, const RenderControl& control,
               const Scene& scene, const Visibility& visibility, std::string_view atOnce = {})
      : RenderDriver(control, scene, visibility, beginRender(table, options, control, scene, atOnce)) {}
  RenderDriver(const RenderControl& control, const Scene& scene, const Visibility& visibility, const RenderPart& part);
  RenderDriver(const RenderDriver&) = delete;
  RenderDriver& operator=(const RenderDriver&) = delete;

  const RenderPart& part() const { return part_; }
  const RenderControl& control() const { return control_; }
  bool stopRequested() const { return control_.stopRequested(); }
  // The fraction of the render done, for a method that counts it by its stages.
  void reportProgress(double fraction) const {
    if (control_.progress) control_.progress(fraction);
  }

  // The film the render adds to: empty, or a copy of control.resume, which must be a film of this
  // part with this layout (std::invalid_argument otherwise); with features, what its pixels show
  // (tracePixelSurfaces) and the scene's material names.
  Film& startFilm(Film::Sums sums, FilmLayers layers);
  Film& film() { return *film_; }
  // The camera samples the film's pixels have taken, summed.
  uint64_t samplesTaken() const;

  // The part's rows in bands, from the first row the film does not hold in full (a resumed render),
  // each to `renderBand`. Between bands: stop requests, progress, and checkpoints of the film.
  // Returns false when a stop ended the loop; a band that a stop interrupts (RenderStopped) is
  // dropped whole.
  bool renderBands(const BandLoop& loop, const BandRenderer& renderBand);

  // One pass over the tiles of `area` (the image's grid of tileSize-pixel squares, cut to the area),
  // in parallel, each by renderTile, which returns the camera samples it took. A stop request ends
  // the pass between tiles (renderTile may end its tile early too, between pixels: stopped() tells).
  // With `countProgress`, each tile's samples count towards expectSamples' total.
  using TileRenderer = std::function<uint64_t(const PixelRect& tile)>;
  void renderTiles(const PixelRect& area, int tileSize, const TileRenderer& renderTile, bool countProgress);
  // The camera samples the film will have when the render ends, for progress.
  void expectSamples(double total) { expectedSamples_ = total; }
  // A pass over the film is done: a checkpoint of it when one is due (none once stopped).
  void passDone();
  bool stopped() const { return stopped_; }

  // The image of a method that shades every camera sample of its part at once: a film (PerPart sums)
  // started as startFilm does, the shading points' light added, every pixel's samples taken; sets
  // out's image, film and sppDone, and times stage "image" (no finish needed).
  void shadeAtOnce(RenderOutput& out, const EyePaths& eye, const PointRadiance& light, FilmLayers layers);

  // The output: the film's image and the film, whether every pixel has all the part's samples, and
  // the samples every pixel has.
  void finish(RenderOutput& out) const;

 private:
  const RenderControl& control_;
  const Scene& scene_;
  const Visibility& visibility_;
  RenderPart part_;
  // Calls control.checkpoint when control.checkpointSeconds have passed since the last call (or the
  // start) and a checkpoint is wanted.
  void checkpointIfDue();

  std::shared_ptr<Film> film_;
  Stopwatch sinceCheckpoint_;
  std::atomic<uint64_t> samplesDone_{0};
  double expectedSamples_ = 1;
  std::atomic<bool> stopped_{false};
};

}  // namespace lucent
