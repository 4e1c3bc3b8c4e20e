#include "lucent/core/parallel.h"
#include "lucent/pipeline/film.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <memory>
#include <stdexcept>

#include "lucent/core/memory.h"

namespace lucent {

namespace {
constexpr size_t kPointChunk = 8192;  // shading points per task when they are added
}  // namespace

const std::vector<PathLayer>& pathLayers() {
  using P = PathParts;
  static const std::vector<PathLayer> layers = {
      {"emission", {P::emission()}},
      {"direct", {P::part(P::Direct, false), P::part(P::Direct, true)}},
      {"direct.diffuse", {P::part(P::Direct, false)}},
      {"direct.glossy", {P::part(P::Direct, true)}},
      {"indirect.1", {P::part(P::Indirect1, false), P::part(P::Indirect1, true)}},
      {"indirect.1.diffuse", {P::part(P::Indirect1, false)}},
      {"indirect.1.glossy", {P::part(P::Indirect1, true)}},
      {"indirect.2", {P::part(P::Indirect2, false), P::part(P::Indirect2, true)}},
      {"indirect.2.diffuse", {P::part(P::Indirect2, false)}},
      {"indirect.2.glossy", {P::part(P::Indirect2, true)}},
      {"indirect.3+", {P::part(P::Indirect3Plus, false), P::part(P::Indirect3Plus, true)}},
      {"indirect.3+.diffuse", {P::part(P::Indirect3Plus, false)}},
      {"indirect.3+.glossy", {P::part(P::Indirect3Plus, true)}},
      {"diffuse", {P::part(P::Direct, false), P::part(P::Indirect1, false), P::part(P::Indirect2, false),
                   P::part(P::Indirect3Plus, false)}},
      {"glossy", {P::part(P::Direct, true), P::part(P::Indirect1, true), P::part(P::Indirect2, true),
                  P::part(P::Indirect3Plus, true)}},
  };
  return layers;
}

PointRadiance::PointRadiance(size_t n) {
  for (UninitializedVector<Rgb>* part : {&direct, &indirect, &caustic}) {
    part->resize(n);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, size_t(1) << 16), [&](const tbb::blocked_range<size_t>& r) {
      std::uninitialized_value_construct(part->data() + r.begin(), part->data() + r.end());
    });
  }
}

Film::Film(int width, int height, PixelRect region, Sums sums, FilmLayers layers)
    : width_(width), height_(height), region_(region), wholeImage_(region == PixelRect{0, 0, width, height}),
      mode_(sums), layers_(layers) {
  if (region.empty() || !PixelRect{0, 0, width, height}.contains(region))
    throw std::invalid_argument("film: the region is not a non-empty part of the image");
  // A caustic part only where shading points' light comes in parts (a film file may claim one for
  // per-sample sums: it has none).
  layers_.caustic = layers.features && layers.caustic && sums == Sums::PerPart;
  auto reserve = [&](int& offset, int channels) { offset = stride_, stride_ += channels; };
  if (layers.variance && sums != Sums::PerSample)
    throw std::invalid_argument("film: a variance layer needs each camera sample's total (Sums::PerSample)");
  if (layers.paths && sums != Sums::PerSample)
    throw std::invalid_argument("film: light split by path needs each camera sample's parts (Sums::PerSample)");
  // Without layers the parts need not be kept apart: the exact sum of every part's terms in one
  // total is the sum of the parts' exact sums, bit for bit, in a third of the memory.
  if (sums == Sums::PerSample || !layers.features) reserve(total_, 3);
  if (layers.variance) reserve(squares_, 3);
  if (layers.features) reserve(direct_, 3), reserve(indirect_, 3);
  if (sums == Sums::PerPart && layers.features) reserve(caustic_, 3);
  if (layers.features) reserve(features_, 7);
  if (layers.paths) reserve(pathParts_, 3 * PathParts::kCount);
  if (layers.paths && layers.variance) reserve(pathSquares_, 3 * int(pathLayers().size()));
  const uint64_t pixels = region.pixelCount();
  // The sums and sample counts, and the image made of them (about as many channels, in floats).
  requireMemory(pixels * (uint64_t(stride_) * (sizeof(ExactSum) + sizeof(float)) + 3 * sizeof(uint32_t)), "the film",
                "lower --resolution or render it in parts (--crop)");
  sums_.resize(pixels * size_t(stride_));
  tbb::parallel_for(tbb::blocked_range<size_t>(0, sums_.size(), size_t(1) << 16), [&](const tbb::blocked_range<size_t>& r) {
    std::uninitialized_value_construct(sums_.data() + r.begin(), sums_.data() + r.end());
  });
  samples_.assign(pixels, 0);
  taken_.assign(pixels, 0);
  if (layers.features) surfaces_.assign(pixels, PixelSurface::kUnknown);
}

void Film::setSurfaces(std::vector<uint32_t> codes, std::vector<std::string> materialNames) {
  if (!layers_.features || codes.size() != surfaces_.size())
    throw std::logic_error("film: pixel surfaces for a film without features, or of another region");
  surfaces_ = std::move(codes);
  materialNames_ = std::move(materialNames);
}

void Film::addSample(uint64_t pixel, Rgb direct, Rgb indirect, Rgb albedo, Vec3 normal, float depth,
                     const PathParts& paths) {
  const size_t p = local(pixel);
  ExactSum* sum = &sums_[p * size_t(stride_)];
  ++samples_[p];
  // The total is summed apart from its parts: (direct + indirect) rounded once per sample.
  const Rgb total = direct + indirect;
  for (int c = 0; c < 3; ++c) sum[total_ + c].add(total[c]);
  if (layers_.variance)
    for (int c = 0; c < 3; ++c) sum[squares_ + c].add(std::min(total[c] * total[c], ExactSum::kMaxTerm));
  if (layers_.paths) {
    for (int k = 0; k < PathParts::kCount; ++k)
      for (int c = 0; c < 3; ++c) sum[pathParts_ + 3 * k + c].add(paths.light[size_t(k)][c]);
    if (layers_.variance) {
      const std::vector<PathLayer>& layers = pathLayers();
      for (size_t l = 0; l < layers.size(); ++l) {
        Rgb light(0.0f);
        for (const int k : layers[l].parts) light += paths.light[size_t(k)];
        for (int c = 0; c < 3; ++c)
          sum[pathSquares_ + 3 * int(l) + c].add(std::min(light[c] * light[c], ExactSum::kMaxTerm));
      }
    }
  }
  if (!layers_.features) return;
  const float features[7] = {albedo.r, albedo.g, albedo.b, normal.x, normal.y, normal.z, depth};
  for (int c = 0; c < 7; ++c) sum[features_ + c].add(features[c]);
  for (int c = 0; c < 3; ++c) sum[direct_ + c].add(direct[c]), sum[indirect_ + c].add(indirect[c]);
}

void Film::add(const EyePaths& band, const PointRadiance& light) {
  if (layers_.features && band.features.size() != band.pixels.size())
    throw std::logic_error("a film with layers takes camera paths traced with layers");
  // Pixels are independent, and a pixel's points are consecutive (by tile, then pixel): both loops
  // run in parallel, the points' in chunks cut where the pixel changes.
  tbb::parallel_for(tbb::blocked_range<size_t>(0, band.pixels.size(), kItemsPerTask), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) {
      const EyePixel& px = band.pixels[i];
      const uint64_t p = band.imagePixel(i, width_);
      ExactSum* sum = at(p);
      samples_[local(p)] += px.validSamples;
      const int emitted = layers_.features ? direct_ : total_;
      for (int c = 0; c < 3; ++c) sum[emitted + c].add(px.emitted[c]);
      if (!layers_.features) continue;
      for (int c = 0; c < 7; ++c) sum[features_ + c].add(band.features[i].sums[c]);
    }
  });
  const size_t n = band.points.size();
  auto chunkStart = [&](size_t k) {  // the first point of chunk k whose pixel differs from the one before
    size_t i = std::min(n, k * kPointChunk);
    while (i > 0 && i < n && band.points[i].pixel == band.points[i - 1].pixel) ++i;
    return i;
  };
  const size_t chunks = (n + kPointChunk - 1) / kPointChunk;
  std::atomic<uint64_t> dropped{0};
  tbb::parallel_for(tbb::blocked_range<size_t>(0, chunks, 1), [&](const tbb::blocked_range<size_t>& r) {
    uint64_t droppedHere = 0;
    for (size_t i = chunkStart(r.begin()), end = chunkStart(r.end()); i < end; ++i) {
      const ShadingPoint& sp = band.points[i];
      const Rgb d = sp.weight * light.direct[i], ind = sp.weight * light.indirect[i], ca = sp.weight * light.caustic[i];
      if (!summable(d) || !summable(ind) || !summable(ca)) {
        ++droppedHere;
        continue;
      }
      ExactSum* sum = at(sp.pixel);
      if (layers_.features)
        for (int c = 0; c < 3; ++c) sum[direct_ + c].add(d[c]), sum[indirect_ + c].add(ind[c]), sum[caustic_ + c].add(ca[c]);
      else
        for (int c = 0; c < 3; ++c) sum[total_ + c].add(d[c]), sum[total_ + c].add(ind[c]), sum[total_ + c].add(ca[c]);
    }
    dropped += droppedHere;
  });
  dropped_ += dropped;
}

void Film::add(const Film& part) {
  if (part.width_ != width_ || part.height_ != height_ || part.mode_ != mode_ || !(part.layers_ == layers_) ||
      part.stride_ != stride_ || !region_.contains(part.region_))
    throw std::invalid_argument("film: a part of another image, layout or region");
  if (layers_.features && part.materialNames_ != materialNames_)
    throw std::invalid_argument("film: a part of a scene with other materials");
  const PixelRect& r = part.region_;
  for (int y = r.y0; y < r.y1; ++y)
    for (int x = r.x0; x < r.x1; ++x) {
      const uint64_t pixel = uint64_t(y) * uint64_t(width_) + uint64_t(x);
      const size_t from = part.local(pixel), to = local(pixel);
      for (int c = 0; c < stride_; ++c) sums_[to * stride_ + c].add(part.sums_[from * stride_ + c]);
      samples_[to] += part.samples_[from];
      taken_[to] += part.taken_[from];
      if (!layers_.features || part.surfaces_[from] == PixelSurface::kUnknown) continue;
      if (surfaces_[to] != PixelSurface::kUnknown && surfaces_[to] != part.surfaces_[from])
        throw std::invalid_argument("film: a part whose pixel (" + std::to_string(x) + ", " + std::to_string(y) +
                                    ") shows another surface");
      surfaces_[to] = part.surfaces_[from];
    }
  dropped_ += part.dropped_;
}

Image Film::image() const {
  std::vector<std::string> channels = {"R", "G", "B"};
  if (layers_.features)
    for (const char* name : {"albedo.R", "albedo.G", "albedo.B", "normal.X", "normal.Y", "normal.Z", "depth.Z",
                             "direct.R", "direct.G", "direct.B", "indirect.R", "indirect.G", "indirect.B"})
      channels.push_back(name);
  if (layers_.caustic)
    for (const char* name : {"caustic.R", "caustic.G", "caustic.B"}) channels.push_back(name);
  const size_t varianceAt = channels.size();
  if (layers_.variance)
    for (const char* name : {"variance.R", "variance.G", "variance.B"}) channels.push_back(name);
  const size_t pathsAt = channels.size();
  const std::vector<PathLayer>& layers = pathLayers();
  if (layers_.paths)
    for (const PathLayer& layer : layers) {
      for (const char* c : {".R", ".G", ".B"}) channels.push_back(std::string("paths.") + layer.name + c);
      if (layers_.variance)
        for (const char* c : {".variance.R", ".variance.G", ".variance.B"})
          channels.push_back(std::string("paths.") + layer.name + c);
    }
  const size_t surfaceAt = channels.size();
  // In the order an EXR file keeps them (by name), so that a read image has the film's layout.
  if (layers_.features)
    for (const char* name : {"surface.emitter", "surface.material"}) channels.push_back(name);
  const size_t nc = channels.size(), pixels = region_.pixelCount();
  Image image(region_.width(), region_.height(), channels);
  float* out = image.pixels().data();
  tbb::parallel_for(tbb::blocked_range<size_t>(0, pixels, kItemsPerTask), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t p = r.begin(); p != r.end(); ++p) {
      const ExactSum* sum = &sums_[p * size_t(stride_)];
      const double n = std::max<uint32_t>(1, samples_[p]);
      float* o = out + p * nc;
      for (int c = 0; c < 3; ++c) {
        ExactSum total = sum[total_ >= 0 ? total_ + c : direct_ + c];
        if (total_ < 0) total.add(sum[indirect_ + c]), total.add(sum[caustic_ + c]);
        o[c] = float(total.value() / n);
      }
      // The sample variance over n, the variance of the pixel's mean (infinite below two samples).
      if (layers_.variance)
        for (int c = 0; c < 3; ++c) {
          const double mean = sum[total_ + c].value() / n;
          const double variance = (sum[squares_ + c].value() / n - mean * mean) * n / (n - 1);
          o[varianceAt + size_t(c)] = samples_[p] < 2 ? kInf : float(std::max(0.0, variance) / n);
        }
      if (layers_.paths) {
        float* to = o + pathsAt;
        for (size_t l = 0; l < layers.size(); ++l) {
          for (int c = 0; c < 3; ++c) {
            // A layer's sum is the exact sum of its parts' sums.
            ExactSum light;
            for (const int k : layers[l].parts) light.add(sum[pathParts_ + 3 * k + c]);
            const double mean = light.value() / n;
            *to++ = float(mean);
            if (layers_.variance) {
              const double variance = (sum[pathSquares_ + 3 * int(l) + c].value() / n - mean * mean) * n / (n - 1);
              to[2] = samples_[p] < 2 ? kInf : float(std::max(0.0, variance) / n);
            }
          }
          if (layers_.variance) to += 3;
        }
      }
      if (!layers_.features) continue;
      o[surfaceAt] = PixelSurface::emits(surfaces_[p]) ? 1.0f : 0.0f;
      o[surfaceAt + 1] = float(PixelSurface::material(surfaces_[p]));
      for (int c = 0; c < 7; ++c) o[3 + c] = float(sum[features_ + c].value() / n);
      for (int c = 0; c < 3; ++c)
        o[10 + c] = float(sum[direct_ + c].value() / n), o[13 + c] = float(sum[indirect_ + c].value() / n);
      if (layers_.caustic)
        for (int c = 0; c < 3; ++c) o[16 + c] = float(sum[caustic_ + c].value() / n);
    }
  });
  return image;
}

}  // namespace lucent
