// The film every method writes its image to: per pixel, exact sums (ExactSum) of the light its
// camera samples bring and of the first hit's features for the auxiliary layers (--layers), and the
// camera samples taken; the image divides each sum by the pixel's valid samples. The sums do not
// depend on the order in which samples are added, so the image depends neither on threads and
// tiles nor on how a render was split into regions and sample ranges, resumed and merged. A film
// covers a region of the image (a crop), all of it by default.
#pragma once
#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "lucent/core/exact_sum.h"
#include "lucent/core/uninitialized.h"
#include "lucent/image/image.h"
#include "lucent/pipeline/pixel_rect.h"
#include "lucent/pipeline/shading_points.h"

namespace lucent {

// The layers an image carries beside R, G, B: none, or the first hit's albedo, normal and depth
// and the light split into direct and indirect parts, with a caustic part for the methods that
// have one.
struct FilmLayers {
  bool features = false;  // albedo, normal, depth, direct, indirect
  bool caustic = false;   // and caustic (only with features)
  bool variance = false;  // Sums::PerSample: the variance of each pixel's mean, from its samples' squares
  bool paths = false;     // Sums::PerSample: the light split by path (PathParts), each part with its variance
  bool operator==(const FilmLayers&) const = default;
};

// A camera sample's light split by the path that brought it: emission seen directly (also through
// mirrors and glass), then direct light (gathered at the path's first non-specular vertex) and
// indirect light by bounce (at its second, third, and fourth or later), each of these split by how
// the first non-specular vertex reflected it, diffusely or glossily (by the diffuse lobe's share of
// the BSDF's value in the direction the path left it: unbiased per part, whichever lobe was sampled).
// The parts add up to the sample's light.
struct PathParts {
  enum Bounce { Direct, Indirect1, Indirect2, Indirect3Plus };
  static constexpr int kCount = 9;
  std::array<Rgb, kCount> light{};  // emission, then per bounce its diffuse and glossy part
  static constexpr int emission() { return 0; }
  static constexpr int part(Bounce bounce, bool glossy) { return 1 + 2 * int(bounce) + int(glossy); }
  // Light gathered after `verticesBefore` non-specular vertices (0: emission seen directly), with
  // the first vertex's diffuse share.
  void gather(int verticesBefore, Rgb contribution, Rgb diffuseShare) {
    if (verticesBefore == 0) {
      light[emission()] += contribution;
      return;
    }
    const Bounce bounce = Bounce(std::min(verticesBefore, 4) - 1);
    const Rgb diffuse = contribution * diffuseShare;
    light[size_t(part(bounce, false))] += diffuse;
    light[size_t(part(bounce, true))] += contribution - diffuse;
  }
};

// The layers of FilmLayers::paths, each a sum of PathParts: channels "paths.NAME.R", .G, .B and,
// with variance, "paths.NAME.variance.R", .G, .B.
struct PathLayer {
  const char* name;
  std::vector<int> parts;
};
const std::vector<PathLayer>& pathLayers();

// Per shading point, the light each part of the estimate sends towards the camera (before the
// point's camera-path weight).
struct PointRadiance {
  UninitializedVector<Rgb> direct, indirect, caustic;
  explicit PointRadiance(size_t n);  // all zero, written in parallel
};

class Film {
 public:
  // How the image's total light is summed, each way for the methods that add light that way:
  // PerSample, each camera sample's total (the path tracer); PerPart, the light of shading points
  // by part (emission and direct light, indirect, caustic: the methods that shade points), kept
  // apart for the layers and summed into one total without them.
  enum class Sums { PerSample, PerPart };
  // A film of the pixels of `region` in a width x height image.
  Film(int width, int height, PixelRect region, Sums sums, FilmLayers layers);
  Film(int width, int height, Sums sums, FilmLayers layers) : Film(width, height, {0, 0, width, height}, sums, layers) {}

  // Sums::PerSample: one camera sample of `pixel` (an index in the whole image), its light split
  // into direct and indirect, both summable(), and by path (read with layers().paths; each part
  // summable()).
  void addSample(uint64_t pixel, Rgb direct, Rgb indirect, Rgb albedo, Vec3 normal, float depth,
                 const PathParts& paths = {});
  // Sums::PerPart: a band of camera samples, then the light of its shading points (each times its
  // camera-path weight). A point whose light is not summable() is left out and counted.
  void add(const EyePaths& band, const PointRadiance& light);
  uint64_t droppedPoints() const { return dropped_; }

  // With features: what each pixel of the region shows (PixelSurface codes, row by row), and the
  // scene's material names the codes index; set once, by the render's start.
  void setSurfaces(std::vector<uint32_t> codes, std::vector<std::string> materialNames);
  std::span<uint32_t> pixelSurfaces() { return surfaces_; }
  std::span<const uint32_t> pixelSurfaces() const { return surfaces_; }
  const std::vector<std::string>& materialNames() const { return materialNames_; }
  void setMaterialNames(std::vector<std::string> names) { materialNames_ = std::move(names); }

  // Camera samples taken at a pixel (valid or not), from the first of the render's sample range:
  // where a checkpoint's render resumes. Methods set it as they finish a pixel's samples.
  void setTaken(uint64_t pixel, uint32_t taken) { taken_[local(pixel)] = taken; }
  uint32_t taken(uint64_t pixel) const { return taken_[local(pixel)]; }

  // The region's pixels: R, G, B, then the layers' channels.
  Image image() const;

  // Another film of the same image, layout and layers whose region lies inside this one's: its
  // sums, valid samples and samples taken are added to this film's, and its pixels' surfaces (which
  // must agree with this film's where both know them) taken.
  void add(const Film& part);

  // The state, as film files store it (pipeline/film_file.h).
  int imageWidth() const { return width_; }
  int imageHeight() const { return height_; }
  const PixelRect& region() const { return region_; }
  Sums sums() const { return mode_; }
  FilmLayers layers() const { return layers_; }
  int sumsPerPixel() const { return stride_; }
  std::span<ExactSum> pixelSums() { return sums_; }
  std::span<const ExactSum> pixelSums() const { return sums_; }
  std::span<uint32_t> validSamples() { return samples_; }
  std::span<const uint32_t> validSamples() const { return samples_; }
  std::span<uint32_t> samplesTaken() { return taken_; }
  std::span<const uint32_t> samplesTaken() const { return taken_; }

 private:
  size_t local(uint64_t pixel) const {
    if (wholeImage_) return size_t(pixel);
    const int x = int(pixel % uint64_t(width_)), y = int(pixel / uint64_t(width_));
    return size_t(y - region_.y0) * size_t(region_.width()) + size_t(x - region_.x0);
  }
  ExactSum* at(uint64_t pixel) { return &sums_[local(pixel) * size_t(stride_)]; }
  int width_, height_;
  PixelRect region_;
  bool wholeImage_;
  Sums mode_;
  FilmLayers layers_;
  // Offsets into a pixel's sums: the total (PerSample, or PerPart without layers), the parts, the
  // features; -1 where absent.
  int total_ = -1, squares_ = -1, direct_ = -1, indirect_ = -1, caustic_ = -1, features_ = -1, stride_ = 0;
  // With paths: the parts' sums (3 per part), and with variance each path layer's squares (3 per layer).
  int pathParts_ = -1, pathSquares_ = -1;
  UninitializedVector<ExactSum> sums_;  // zeroed in parallel: a film can be hundreds of megabytes
  std::vector<uint32_t> samples_;  // valid camera samples per pixel
  std::vector<uint32_t> taken_;    // camera samples taken per pixel
  std::vector<uint32_t> surfaces_; // with features: PixelSurface codes per pixel
  std::vector<std::string> materialNames_;
  uint64_t dropped_ = 0;
};

}  // namespace lucent
