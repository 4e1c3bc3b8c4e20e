// The pipeline's film: what it sums per pixel, its layers, and what it leaves out.
#include <catch2/catch.hpp>

#include <limits>

#include "lucent/pipeline/film.h"

using namespace lucent;

namespace {

// A band of a 2 x 2 image, one camera sample per pixel that saw emission 0.25, and a shading
// point in each of the first three pixels with direct light 1.
struct TwoByTwo {
  EyePaths eye;
  PointRadiance light{3};
  TwoByTwo() {
    eye.region = {0, 0, 2, 2};
    eye.pixels.resize(4);
    eye.features.resize(4);
    for (size_t i = 0; i < 4; ++i) {
      eye.pixels[i] = EyePixel{};
      eye.pixels[i].addSample(Rgb(0.25f));
      eye.features[i] = EyeFeatures{};
      eye.features[i].add(FirstHit{Rgb(0.5f), Vec3(0, 1, 0), 2});
    }
    eye.points.resize(3);
    for (uint32_t i = 0; i < 3; ++i) {
      eye.points[i] = ShadingPoint{};
      eye.points[i].weight = Rgb(1.0f);
      eye.points[i].pixel = i;
      light.direct[i] = Rgb(1.0f);
    }
  }
};

}  // namespace

TEST_CASE("A shading point whose light is not finite is left out of the image and counted", "[film]") {
  TwoByTwo band;
  band.light.indirect[1] = Rgb(std::numeric_limits<float>::quiet_NaN());
  band.light.caustic[2] = Rgb(kInf);
  Film film(2, 2, Film::Sums::PerPart, {});
  film.add(band.eye, band.light);
  const Image image = film.image();
  CHECK(film.droppedPoints() == 2);
  CHECK(image.at(0, 0, 0) == 1.25f);
  CHECK(image.at(1, 0, 0) == 0.25f);
  CHECK(image.at(0, 1, 0) == 0.25f);
}

TEST_CASE("The film's layers: features and parts, and a caustic part only where asked for", "[film]") {
  TwoByTwo band;
  band.light.indirect[0] = Rgb(0.5f);
  band.light.caustic[0] = Rgb(2.0f);
  for (const bool caustic : {false, true}) {
    Film film(2, 2, Film::Sums::PerPart, {true, caustic});
    film.add(band.eye, band.light);
    const Image image = film.image();
    CHECK(image.channelCount() == (caustic ? 21 : 18));  // with surface.material and surface.emitter
    CHECK(image.channelIndex("caustic.R") == (caustic ? 16 : -1));
    CHECK(image.at(0, 0, image.channelIndex("R")) == 3.75f);  // the caustic part is in the total either way
    CHECK(image.at(0, 0, image.channelIndex("direct.G")) == 1.25f);
    CHECK(image.at(0, 0, image.channelIndex("indirect.B")) == 0.5f);
    CHECK(image.at(0, 0, image.channelIndex("albedo.R")) == 0.5f);
    CHECK(image.at(0, 0, image.channelIndex("normal.Y")) == 1.0f);
    CHECK(image.at(0, 0, image.channelIndex("depth.Z")) == 2.0f);
    if (caustic) CHECK(image.at(0, 0, image.channelIndex("caustic.R")) == 2.0f);
  }
  // Per sample: each sample's total, averaged over the pixel's samples.
  Film film(2, 2, Film::Sums::PerSample, {true, false});
  film.addSample(3, Rgb(1.0f), Rgb(0.5f), Rgb(0.2f), Vec3(0, 0, 1), 4);
  film.addSample(3, Rgb(3.0f), Rgb(0.5f), Rgb(0.4f), Vec3(0, 0, 1), 2);
  const Image image = film.image();
  CHECK(image.channelCount() == 18);
  CHECK(image.at(1, 1, 0) == 2.5f);
  CHECK(image.at(1, 1, image.channelIndex("direct.R")) == 2.0f);
  CHECK(image.at(1, 1, image.channelIndex("albedo.G")) == Approx(0.3f));
  CHECK(image.at(1, 1, image.channelIndex("depth.Z")) == 3.0f);
  CHECK(image.at(0, 0, 0) == 0.0f);  // no sample
}

TEST_CASE("Without layers a film keeps one total per channel, and its image is the parts' to the bit", "[film]") {
  // Parts whose float sum rounds differently from their exact sum: 1 + 2^-24 + 2^-24 is 1 in float
  // arithmetic, 1 + 2^-23 exactly.
  TwoByTwo band;
  for (uint32_t i = 0; i < 3; ++i)
    band.light.direct[i] = Rgb(1.0f), band.light.indirect[i] = Rgb(0x1p-24f * float(i + 1)),
    band.light.caustic[i] = Rgb(0x1p-24f);
  Film total(2, 2, Film::Sums::PerPart, {});
  Film parts(2, 2, Film::Sums::PerPart, {true, true});
  CHECK(total.sumsPerPixel() == 3);
  CHECK(parts.sumsPerPixel() == 3 + 3 + 3 + 7);
  total.add(band.eye, band.light);
  parts.add(band.eye, band.light);
  const Image a = total.image(), b = parts.image();
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 2; ++x)
      for (int c = 0; c < 3; ++c) {
        INFO("pixel " << x << ", " << y << ", channel " << c);
        CHECK(a.at(x, y, c) == b.at(x, y, b.channelIndex(std::string(1, "RGB"[c]))));
      }
  CHECK(a.at(0, 0, 0) == float(1.25 + 0x1p-23));  // the pixel's parts, summed exactly
}

TEST_CASE("A film's pixel surfaces become the surface layers, and parts must agree on them", "[film]") {
  const std::vector<std::string> names = {"wall", "lamp"};
  const std::vector<uint32_t> codes = {PixelSurface::code(0, false), PixelSurface::code(1, true),
                                       PixelSurface::code(-1, false), PixelSurface::code(-1, true)};
  Film film(2, 2, Film::Sums::PerSample, {true, false});
  film.setSurfaces(codes, names);
  const Image image = film.image();
  const int material = image.channelIndex("surface.material"), emitter = image.channelIndex("surface.emitter");
  REQUIRE(material >= 0);
  REQUIRE(emitter >= 0);
  CHECK(image.at(0, 0, material) == 0.0f);
  CHECK(image.at(0, 0, emitter) == 0.0f);
  CHECK(image.at(1, 0, material) == 1.0f);
  CHECK(image.at(1, 0, emitter) == 1.0f);
  CHECK(image.at(0, 1, material) == -1.0f);  // the background
  CHECK(image.at(1, 1, emitter) == 1.0f);    // an environment's background emits
  CHECK(Film(2, 2, Film::Sums::PerSample, {}).image().channelIndex("surface.material") == -1);

  // A merge takes the parts' surfaces; a part that saw another surface, or another scene's
  // materials, is refused.
  Film part(2, 2, {0, 1, 2, 2}, Film::Sums::PerSample, {true, false});
  part.setSurfaces({codes[2], codes[3]}, names);
  Film whole(2, 2, Film::Sums::PerSample, {true, false});
  whole.setMaterialNames(names);
  whole.add(part);
  CHECK(whole.pixelSurfaces()[2] == codes[2]);
  CHECK(whole.pixelSurfaces()[0] == PixelSurface::kUnknown);
  whole.add(film);
  CHECK(std::vector<uint32_t>(whole.pixelSurfaces().begin(), whole.pixelSurfaces().end()) == codes);
  Film other(2, 2, {0, 1, 2, 2}, Film::Sums::PerSample, {true, false});
  other.setSurfaces({codes[3], codes[3]}, names);
  CHECK_THROWS_WITH(whole.add(other), Catch::Contains("pixel (0, 1) shows another surface"));
  Film renamed(2, 2, {0, 1, 2, 2}, Film::Sums::PerSample, {true, false});
  renamed.setSurfaces({codes[2], codes[3]}, {"wall", "light"});
  CHECK_THROWS_WITH(whole.add(renamed), Catch::Contains("other materials"));
}
