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
    CHECK(image.channelCount() == (caustic ? 19 : 16));
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
  CHECK(image.channelCount() == 16);
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
