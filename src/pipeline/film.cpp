#include "lucent/pipeline/film.h"

#include <algorithm>

#include "lucent/core/memory.h"

namespace lucent {

Film::Film(int width, int height, Sums sums, FilmLayers layers) : width_(width), height_(height), mode_(sums), layers_(layers) {
  layers_.caustic = layers.features && layers.caustic;
  // The parts are kept wherever the image needs them: for the layers, or (PerPart) for the total.
  auto reserve = [&](int& offset, int channels) { offset = stride_, stride_ += channels; };
  if (sums == Sums::PerSample) reserve(total_, 3);
  if (sums == Sums::PerPart || layers.features) reserve(direct_, 3), reserve(indirect_, 3);
  if (sums == Sums::PerPart) reserve(caustic_, 3);
  if (layers.features) reserve(features_, 7);
  const uint64_t pixels = uint64_t(width) * uint64_t(height);
  // The sums and sample counts, and the image made of them (about as many channels, in floats).
  requireMemory(pixels * (uint64_t(stride_) * (sizeof(double) + sizeof(float)) + sizeof(uint32_t)), "the film",
                "lower --resolution");
  sums_.assign(size_t(width) * size_t(height) * size_t(stride_), 0.0);
  samples_.assign(size_t(width) * size_t(height), 0);
}

void Film::addSample(uint64_t pixel, Rgb direct, Rgb indirect, Rgb albedo, Vec3 normal, float depth) {
  double* sum = at(pixel);
  const Rgb total = direct + indirect;
  for (int c = 0; c < 3; ++c) sum[total_ + c] += total[c];
  ++samples_[pixel];
  if (!layers_.features) return;
  const float features[7] = {albedo.r, albedo.g, albedo.b, normal.x, normal.y, normal.z, depth};
  for (int c = 0; c < 7; ++c) sum[features_ + c] += features[c];
  for (int c = 0; c < 3; ++c) sum[direct_ + c] += direct[c], sum[indirect_ + c] += indirect[c];
}

void Film::add(const EyePaths& band, const PointRadiance& light) {
  for (size_t i = 0; i < band.pixels.size(); ++i) {
    const EyePixel& px = band.pixels[i];
    const uint64_t p = band.firstPixel + i;
    double* sum = at(p);
    samples_[p] += px.validSamples;
    for (int c = 0; c < 3; ++c) sum[direct_ + c] += px.emitted[c];
    if (!layers_.features) continue;
    const float features[7] = {px.albedo.r, px.albedo.g, px.albedo.b, px.normal.x, px.normal.y, px.normal.z, px.depth};
    for (int c = 0; c < 7; ++c) sum[features_ + c] += features[c];
  }
  for (size_t i = 0; i < band.points.size(); ++i) {
    const ShadingPoint& sp = band.points[i];
    const Rgb d = sp.weight * light.direct[i], ind = sp.weight * light.indirect[i], ca = sp.weight * light.caustic[i];
    if (!isFinite(d + ind + ca)) {
      ++dropped_;
      continue;
    }
    double* sum = at(sp.pixel);
    for (int c = 0; c < 3; ++c) sum[direct_ + c] += d[c], sum[indirect_ + c] += ind[c], sum[caustic_ + c] += ca[c];
  }
}

Image Film::image() const {
  std::vector<std::string> channels = {"R", "G", "B"};
  if (layers_.features)
    for (const char* name : {"albedo.R", "albedo.G", "albedo.B", "normal.X", "normal.Y", "normal.Z", "depth.Z",
                             "direct.R", "direct.G", "direct.B", "indirect.R", "indirect.G", "indirect.B"})
      channels.push_back(name);
  if (layers_.caustic)
    for (const char* name : {"caustic.R", "caustic.G", "caustic.B"}) channels.push_back(name);
  const size_t nc = channels.size(), pixels = size_t(width_) * size_t(height_);
  Image image(width_, height_, channels);
  float* out = image.pixels().data();
  for (size_t p = 0; p < pixels; ++p) {
    const double* sum = &sums_[p * size_t(stride_)];
    const double n = std::max<uint32_t>(1, samples_[p]);
    float* o = out + p * nc;
    for (int c = 0; c < 3; ++c)
      o[c] = float((mode_ == Sums::PerSample ? sum[total_ + c] : sum[direct_ + c] + sum[indirect_ + c] + sum[caustic_ + c]) / n);
    if (!layers_.features) continue;
    for (int c = 0; c < 7; ++c) o[3 + c] = float(sum[features_ + c] / n);
    for (int c = 0; c < 3; ++c) o[10 + c] = float(sum[direct_ + c] / n), o[13 + c] = float(sum[indirect_ + c] / n);
    if (layers_.caustic)
      for (int c = 0; c < 3; ++c) o[16 + c] = float(sum[caustic_ + c] / n);
  }
  return image;
}

}  // namespace lucent
