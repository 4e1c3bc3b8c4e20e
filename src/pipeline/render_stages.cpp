#include "lucent/pipeline/render_stages.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "lucent/core/stop.h"

namespace lucent {

RenderPart resolvePart(const RenderControl& control, const Scene& scene, int spp) {
  const PixelRect image{0, 0, scene.camera.width, scene.camera.height};
  RenderPart part;
  part.region = control.crop.empty() ? image : control.crop;
  if (!image.contains(part.region))
    throw std::invalid_argument("--crop " + std::to_string(part.region.x0) + "," + std::to_string(part.region.y0) + "," +
                                std::to_string(part.region.x1) + "," + std::to_string(part.region.y1) +
                                ": not inside the " + std::to_string(image.x1) + " x " + std::to_string(image.y1) +
                                " image");
  part.sampleBegin = control.firstSample;
  part.sampleEnd = control.sampleCount > 0 ? control.firstSample + control.sampleCount : spp;
  if (part.sampleBegin < 0 || part.sampleBegin >= part.sampleEnd || part.sampleEnd > spp)
    throw std::invalid_argument("--samples " + std::to_string(control.firstSample) + ":" +
                                std::to_string(control.sampleCount) + ": not inside the " + std::to_string(spp) +
                                " samples per pixel (--spp)");
  return part;
}

void refuseResume(const RenderControl& control, std::string_view atOnce) {
  if (control.resume || control.checkpointSeconds > 0)
    throw std::invalid_argument(std::string(atOnce) + " and cannot checkpoint or resume; render it in parts (--crop, "
                                "--samples) to bound the work a kill loses");
}

Film startFilm(const RenderControl& control, const Scene& scene, const Visibility& visibility, const RenderPart& part,
               Film::Sums sums, FilmLayers layers) {
  Film film(scene.camera.width, scene.camera.height, part.region, sums, layers);
  if (layers.features) film.setSurfaces(tracePixelSurfaces(scene, visibility, part.region), scene.materialNames);
  if (!control.resume) return film;
  const Film& from = *control.resume;
  if (from.imageWidth() != film.imageWidth() || from.imageHeight() != film.imageHeight() ||
      !(from.region() == film.region()) || from.sums() != film.sums() || !(from.layers() == film.layers()))
    throw std::invalid_argument("the film to resume from is of another image, part or layout");
  for (uint32_t taken : from.samplesTaken())
    if (taken > uint32_t(part.samples()))
      throw std::invalid_argument("the film to resume from has more samples than the part");
  film.add(from);
  return film;
}

void addBand(Film& film, const EyePaths& band, const PointRadiance& light, int imageWidth, const RenderPart& part) {
  film.add(band, light);
  for (size_t i = 0; i < band.pixels.size(); ++i) film.setTaken(band.imagePixel(i, imageWidth), uint32_t(part.samples()));
}

void shadeImage(RenderOutput& out, const RenderControl& control, const Scene& scene, const Visibility& visibility,
                const RenderPart& part, const EyePaths& eye, const PointRadiance& light, FilmLayers layers) {
  Stopwatch clock;
  auto film = std::make_shared<Film>(startFilm(control, scene, visibility, part, Film::Sums::PerPart, layers));
  addBand(*film, eye, light, scene.camera.width, part);
  out.image = film->image();
  out.film = film;
  out.sppDone = part.samples();
  out.stats.addStage("image", clock.seconds());
}

bool filmComplete(const Film& film, const RenderPart& part) {
  return std::all_of(film.samplesTaken().begin(), film.samplesTaken().end(),
                     [&](uint32_t taken) { return taken == uint32_t(part.samples()); });
}

void CheckpointClock::reached(const Film& film) {
  if (!(control_.checkpointSeconds > 0) || !control_.checkpoint) return;
  if (sinceLast_.seconds() < control_.checkpointSeconds) return;
  control_.checkpoint(film);
  sinceLast_ = Stopwatch();
}

RowBands::RowBands(const RenderPart& part, uint64_t maxSamples, double targetSeconds)
    : part_(part), targetSeconds_(targetSeconds) {
  const uint64_t rowSamples = uint64_t(part.region.width()) * uint64_t(std::max(1, part.samples()));
  maxRows_ = std::clamp<uint64_t>(maxSamples / rowSamples, 1, uint64_t(part.region.height()));
}

std::pair<int, int> RowBands::next(int row) {
  uint64_t rows = maxRows_;
  if (targetSeconds_ > 0) {
    // Until a band has been timed: a thirty-second of the region.
    const double wanted = secondsPerRow_ > 0 ? targetSeconds_ / secondsPerRow_ : std::ceil(part_.region.height() / 32.0);
    rows = std::clamp<uint64_t>(uint64_t(std::max(1.0, wanted)), 1, maxRows_);
  }
  return {row, int(std::min<uint64_t>(uint64_t(part_.region.y1), uint64_t(row) + rows))};
}

void RowBands::finished(int rows, double seconds) {
  if (rows > 0) secondsPerRow_ = seconds / rows;
}

bool renderRowBands(const RenderControl& control, const RenderPart& part, const BandLoop& loop, const Film& film,
                    const BandRenderer& renderBand) {
  const PixelRect& region = part.region;
  const uint64_t width = uint64_t(film.imageWidth());
  auto rowDone = [&](int y) {
    for (int x = region.x0; x < region.x1; ++x)
      if (film.taken(uint64_t(y) * width + uint64_t(x)) != uint32_t(part.samples())) return false;
    return true;
  };
  int row = region.y0;
  while (row < region.y1 && rowDone(row)) ++row;
  RowBands bands(part, loop.maxSamples, loop.targetSeconds);
  CheckpointClock checkpoints(control);
  const double rows = region.height();
  auto report = [&](double done) {
    if (control.progress) control.progress(loop.progressFrom + (loop.progressTo - loop.progressFrom) * done);
  };
  for (size_t index = 0; row < region.y1; ++index) {
    if (control.stopRequested()) return false;
    Stopwatch bandClock;
    const std::pair<int, int> next = bands.next(row);
    const int first = next.first, end = next.second;
    try {
      renderBand(PixelRect{region.x0, first, region.x1, end}, index,
                 [&](double fraction) { report((double(first - region.y0) + fraction * (end - first)) / rows); });
    } catch (const RenderStopped&) {
      return false;
    }
    bands.finished(end - first, bandClock.seconds());
    row = end;
    report(double(row - region.y0) / rows);
    if (row < region.y1) checkpoints.reached(film);
  }
  return true;
}

EyePathSettings eyePathSettings(const CommonOptions& common, int maxSpecularDepth, const RenderPart& part) {
  EyePathSettings s;
  s.spp = common.spp;
  s.filter = {common.pixelFilter, common.filterRadius};
  s.maxSpecularDepth = maxSpecularDepth;
  s.seed = common.seed;
  s.layers = common.layers;
  s.region = part.region;
  s.sampleBegin = part.sampleBegin;
  s.sampleEnd = part.sampleEnd;
  return s;
}

}  // namespace lucent
