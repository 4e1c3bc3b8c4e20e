// The film every method writes its image to: per pixel, sums in double of the light its camera
// samples bring and of the first hit's features for the auxiliary layers (--layers); the image
// divides each by the pixel's valid samples. Every pixel is written by one work item at a time and
// its samples are added in a fixed order, so the image does not depend on threads or tiles.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "lucent/image/image.h"
#include "lucent/pipeline/shading_points.h"

namespace lucent {

// The layers an image carries beside R, G, B: none, or the first hit's albedo, normal and depth
// and the light split into direct and indirect parts, with a caustic part for the methods that
// have one.
struct FilmLayers {
  bool features = false;  // albedo, normal, depth, direct, indirect
  bool caustic = false;   // and caustic (only with features)
};

// Per shading point, the light each part of the estimate sends towards the camera (before the
// point's camera-path weight).
struct PointRadiance {
  std::vector<Rgb> direct, indirect, caustic;
  explicit PointRadiance(size_t n) : direct(n), indirect(n), caustic(n) {}
};

class Film {
 public:
  // How the image's total light is summed, each way for the methods that add light that way:
  // PerSample, each camera sample's total (the path tracer); PerPart, each part apart (emission
  // and direct light, indirect, caustic: the methods that shade points), added at the end.
  enum class Sums { PerSample, PerPart };
  Film(int width, int height, Sums sums, FilmLayers layers);

  // Sums::PerSample: one valid camera sample of `pixel`, its light split into direct and indirect.
  void addSample(uint64_t pixel, Rgb direct, Rgb indirect, Rgb albedo, Vec3 normal, float depth);
  // Sums::PerPart: a band of camera samples, then the light of its shading points in their order
  // (each times its camera-path weight). A point whose light is not finite is left out and counted.
  void add(const EyePaths& band, const PointRadiance& light);
  uint64_t droppedPoints() const { return dropped_; }

  // R, G, B, then the layers' channels.
  Image image() const;

 private:
  double* at(uint64_t pixel) { return &sums_[pixel * stride_]; }
  int width_, height_;
  Sums mode_;
  FilmLayers layers_;
  // Offsets into a pixel's sums: the total (PerSample), the parts, the features; -1 where absent.
  int total_ = -1, direct_ = -1, indirect_ = -1, caustic_ = -1, features_ = -1, stride_ = 0;
  std::vector<double> sums_;
  std::vector<uint32_t> samples_;  // valid camera samples per pixel
  uint64_t dropped_ = 0;
};

}  // namespace lucent
