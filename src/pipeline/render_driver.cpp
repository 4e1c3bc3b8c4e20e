#include "lucent/pipeline/render_driver.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <utility>
#include <cmath>
#include <stdexcept>

#include "lucent/core/parallel.h"
#include "lucent/core/stop.h"

namespace lucent {

namespace {

Film startingFilm(const RenderControl& control, const Scene& scene, const Visibility& visibility, const RenderPart& part,
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

// Bands of rows of a region, sized by the work: at most `maxSamples` camera samples each (memory),
// and, once the time per row is known, about `targetSeconds` of work.
class RowBands {
 public:
  RowBands(const RenderPart& part, uint64_t maxSamples, double targetSeconds) : part_(part), targetSeconds_(targetSeconds) {
    const uint64_t rowSamples = uint64_t(part.region.width()) * uint64_t(std::max(1, part.samples()));
    maxRows_ = std::clamp<uint64_t>(maxSamples / rowSamples, 1, uint64_t(part.region.height()));
  }
  // The next band [first, second) of rows from `row` on, after the last band took `seconds`.
  std::pair<int, int> next(int row) const {
    uint64_t rows = maxRows_;
    if (targetSeconds_ > 0) {
      // Until a band has been timed: a thirty-second of the region.
      const double wanted = secondsPerRow_ > 0 ? targetSeconds_ / secondsPerRow_ : std::ceil(part_.region.height() / 32.0);
      rows = std::clamp<uint64_t>(uint64_t(std::max(1.0, wanted)), 1, maxRows_);
    }
    return {row, int(std::min<uint64_t>(uint64_t(part_.region.y1), uint64_t(row) + rows))};
  }
  void finished(int rows, double seconds) {
    if (rows > 0) secondsPerRow_ = seconds / rows;
  }

 private:
  RenderPart part_;
  uint64_t maxRows_;
  double targetSeconds_, secondsPerRow_ = 0;
};

}  // namespace

RenderDriver::RenderDriver(const RenderControl& control, const Scene& scene, const Visibility& visibility,
                           const RenderPart& part)
    : control_(control), scene_(scene), visibility_(visibility), part_(part) {}

Film& RenderDriver::startFilm(Film::Sums sums, FilmLayers layers) {
  film_ = std::make_shared<Film>(startingFilm(control_, scene_, visibility_, part_, sums, layers));
  samplesDone_ = samplesTaken();
  return *film_;
}

uint64_t RenderDriver::samplesTaken() const {
  uint64_t sum = 0;
  for (uint32_t taken : film_->samplesTaken()) sum += taken;
  return sum;
}

void RenderDriver::checkpointIfDue() {
  if (!(control_.checkpointSeconds > 0) || !control_.checkpoint) return;
  if (sinceCheckpoint_.seconds() < control_.checkpointSeconds) return;
  control_.checkpoint(*film_);
  sinceCheckpoint_ = Stopwatch();
}

bool RenderDriver::renderBands(const BandLoop& loop, const BandRenderer& renderBand) {
  const PixelRect& region = part_.region;
  const uint64_t width = uint64_t(film_->imageWidth());
  auto rowDone = [&](int y) {
    for (int x = region.x0; x < region.x1; ++x)
      if (film_->taken(uint64_t(y) * width + uint64_t(x)) != uint32_t(part_.samples())) return false;
    return true;
  };
  int row = region.y0;
  while (row < region.y1 && rowDone(row)) ++row;
  RowBands bands(part_, loop.maxSamples, loop.targetSeconds);
  const double rows = region.height();
  auto report = [&](double done) { reportProgress(loop.progressFrom + (loop.progressTo - loop.progressFrom) * done); };
  for (size_t index = 0; row < region.y1; ++index) {
    if (control_.stopRequested()) return false;
    Stopwatch bandClock;
    const std::pair<int, int> next = bands.next(row);  // named apart: Clang's lambdas take no structured bindings
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
    if (row < region.y1) checkpointIfDue();
  }
  return true;
}

void RenderDriver::renderTiles(const PixelRect& area, int tileSize, const TileRenderer& renderTile, bool countProgress) {
  const int tileX0 = area.x0 / tileSize, tileY0 = area.y0 / tileSize;
  const int tilesX = (area.x1 + tileSize - 1) / tileSize - tileX0, tilesY = (area.y1 + tileSize - 1) / tileSize - tileY0;
  tbb::parallel_for(tbb::blocked_range<int>(0, tilesX * tilesY, 1), [&](const tbb::blocked_range<int>& r) {
    flushDenormals();  // every thread computes alike, whoever created it
    for (int t = r.begin(); t != r.end(); ++t) {
      if (control_.stopRequested()) {
        stopped_ = true;
        return;
      }
      const int tx = tileX0 + t % tilesX, ty = tileY0 + t / tilesX;
      const PixelRect tile{std::max(area.x0, tx * tileSize), std::max(area.y0, ty * tileSize),
                           std::min(area.x1, (tx + 1) * tileSize), std::min(area.y1, (ty + 1) * tileSize)};
      const uint64_t taken = renderTile(tile);
      if (control_.stopRequested()) stopped_ = true;  // the tile may have ended before its last pixel
      if (!countProgress) continue;
      const uint64_t samples = samplesDone_ += taken;
      reportProgress(std::min(1.0, double(samples) / expectedSamples_));
    }
  });
}

void RenderDriver::passDone() {
  if (!stopped_) checkpointIfDue();
}

void RenderDriver::shadeAtOnce(RenderOutput& out, const EyePaths& eye, const PointRadiance& light, FilmLayers layers) {
  Stopwatch clock;
  startFilm(Film::Sums::PerPart, layers);
  addBand(*film_, eye, light, scene_.camera.width, part_);
  out.image = film_->image();
  out.film = film_;
  out.sppDone = part_.samples();
  out.stats.addStage("image", clock.seconds());
}

void RenderDriver::finish(RenderOutput& out) const {
  out.image = film_->image();
  out.film = film_;
  out.complete = std::all_of(film_->samplesTaken().begin(), film_->samplesTaken().end(),
                             [&](uint32_t taken) { return taken == uint32_t(part_.samples()); });
  out.sppDone = int(*std::min_element(film_->samplesTaken().begin(), film_->samplesTaken().end()));
}

}  // namespace lucent
