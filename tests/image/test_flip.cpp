// FLIP and HDR-FLIP against what the papers state: each stage's constants and filters, the colour
// pipeline, feature detection, and the whole metric against a direct two-dimensional formulation.
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <numbers>
#include <random>

#include "lucent/image/flip.h"
#include "lucent/image/image.h"
#include "test_support.h"

using namespace lucent;
using Triple = std::array<float, 3>;

namespace {

// A 48 x 40 image of random rectangles of colour with noise on them: edges, points and flat areas.
Image structuredImage(uint32_t seed, float scale, bool lognormal) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0, 1);
  Image image(48, 40, {"R", "G", "B"});
  for (float& v : image.pixels()) v = 0.3f * u(rng);
  for (int k = 0; k < 12; ++k) {
    const int x0 = int(u(rng) * 40), y0 = int(u(rng) * 32), x1 = x0 + 1 + int(u(rng) * 20), y1 = y0 + 1 + int(u(rng) * 20);
    const Triple colour = {u(rng), u(rng), u(rng)};
    for (int y = y0; y < std::min(y1, 40); ++y)
      for (int x = x0; x < std::min(x1, 48); ++x)
        for (int c = 0; c < 3; ++c) image.at(x, y, c) = colour[size_t(c)];
  }
  for (float& v : image.pixels()) v = lognormal ? scale * std::exp(6 * v - 3) : std::min(1.0f, scale * v);
  return image;
}

// The image with noise of the given amplitude added (clamped at 0).
Image noisy(const Image& image, float amplitude, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1, 1);
  Image out = image;
  for (float& v : out.pixels()) v = std::max(0.0f, v * (1 + amplitude * u(rng)) + 0.2f * amplitude * u(rng));
  return out;
}

Image uniform(int w, int h, Triple colour) {
  return test::rgbImage(w, h, [&](int, int) { return Rgb(colour[0], colour[1], colour[2]); });
}

// LDR-FLIP written the direct way: the papers' two-dimensional kernels, built from their formulas in
// double precision and correlated with the image without separating them; an independent
// formulation of the separable filtering the library does.
std::vector<double> directLdrFlip(const Image& candidate, const Image& reference, double ppd) {
  const int w = reference.width(), h = reference.height();
  constexpr double pi = std::numbers::pi;
  const int rc = int(std::ceil(3 * std::sqrt(0.04 / (2 * pi * pi)) * ppd));
  auto csf = [&](std::vector<std::array<double, 2>> gaussians) {  // (a, b) pairs
    std::vector<double> k;
    double sum = 0;
    for (int j = -rc; j <= rc; ++j)
      for (int i = -rc; i <= rc; ++i) {
        const double d2 = (i * i + j * j) / (ppd * ppd);
        double v = 0;
        for (const auto& [a, b] : gaussians) v += a * std::sqrt(pi / b) * std::exp(-pi * pi * d2 / b);
        k.push_back(v);
        sum += v;
      }
    for (double& v : k) v /= sum;
    return k;
  };
  const std::vector<double> kY = csf({{1, 0.0047}}), kCx = csf({{1, 0.0053}}), kCz = csf({{34.1, 0.04}, {13.5, 0.025}});
  const double sd = 0.5 * 0.082 * ppd;
  const int rf = int(std::ceil(3 * sd));
  auto feature = [&](bool edge, bool transpose) {
    std::vector<double> k;
    double positive = 0, negative = 0;
    for (int j = -rf; j <= rf; ++j)
      for (int i = -rf; i <= rf; ++i) {
        const double along = transpose ? j : i;
        const double g = std::exp(-(i * i + j * j) / (2 * sd * sd));
        const double v = edge ? -along * g : (along * along / (sd * sd) - 1) * g;
        k.push_back(v);
        (v > 0 ? positive : negative) += std::abs(v);
      }
    for (double& v : k) v /= v > 0 ? positive : negative;
    return k;
  };
  const std::vector<double> ex = feature(true, false), ey = feature(true, true), px = feature(false, false),
                            py = feature(false, true);
  auto correlate = [&](const std::vector<double>& plane, const std::vector<double>& k, int r, int x, int y) {
    double s = 0;
    for (int j = -r; j <= r; ++j)
      for (int i = -r; i <= r; ++i)
        s += k[size_t((j + r) * (2 * r + 1) + i + r)] *
             plane[size_t(std::clamp(y + j, 0, h - 1) * w + std::clamp(x + i, 0, w - 1))];
    return s;
  };
  struct Stages {
    std::vector<Triple> huntLab;
    std::vector<double> edges, points;
  };
  auto stages = [&](const Image& image) {
    std::array<std::vector<double>, 3> opponent;
    std::vector<double> lum;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        Triple rgb;
        for (int c = 0; c < 3; ++c) rgb[size_t(c)] = std::clamp(image.at(x, y, c), 0.0f, 1.0f);
        const Triple o = flip::linearRgbToYCxCz(rgb);
        for (int c = 0; c < 3; ++c) opponent[size_t(c)].push_back(o[size_t(c)]);
        lum.push_back((o[0] + 16.0) / 116.0);
      }
    Stages s;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        Triple rgb = flip::yCxCzToLinearRgb({float(correlate(opponent[0], kY, rc, x, y)),
                                             float(correlate(opponent[1], kCx, rc, x, y)),
                                             float(correlate(opponent[2], kCz, rc, x, y))});
        for (float& v : rgb) v = std::clamp(v, 0.0f, 1.0f);
        s.huntLab.push_back(flip::linearRgbToHuntLab(rgb));
        s.edges.push_back(std::hypot(correlate(lum, ex, rf, x, y), correlate(lum, ey, rf, x, y)));
        s.points.push_back(std::hypot(correlate(lum, px, rf, x, y), correlate(lum, py, rf, x, y)));
      }
    return s;
  };
  const Stages c = stages(candidate), r = stages(reference);
  std::vector<double> errors;
  for (size_t i = 0; i < c.huntLab.size(); ++i) {
    const double featureDifference =
        std::max(std::abs(c.edges[i] - r.edges[i]), std::abs(c.points[i] - r.points[i]));
    errors.push_back(std::pow(flip::colourError(c.huntLab[i], r.huntLab[i]),
                              1 - std::pow(featureDifference / std::sqrt(2.0), 0.5)));
  }
  return errors;
}

double largestDifference(const Image& map, const std::vector<double>& expected) {
  double largest = 0;
  for (size_t i = 0; i < expected.size(); ++i) largest = std::max(largest, std::abs(map.pixels()[i] - expected[i]));
  return largest;
}

}  // namespace

TEST_CASE("FLIP's colour spaces: D65 white, CIELAB of the primaries, the Hunt adjustment", "[flip]") {
  const Triple white = flip::linearRgbToYCxCz({1, 1, 1});
  CHECK(white[0] == Approx(100).margin(1e-4));
  CHECK(white[1] == Approx(0).margin(1e-4));
  CHECK(white[2] == Approx(0).margin(1e-4));
  // YCxCz and back is the identity.
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0, 1);
  for (int k = 0; k < 100; ++k) {
    const Triple rgb = {u(rng), u(rng), u(rng)};
    const Triple back = flip::yCxCzToLinearRgb(flip::linearRgbToYCxCz(rgb));
    for (int c = 0; c < 3; ++c) CHECK(back[size_t(c)] == Approx(rgb[size_t(c)]).margin(2e-6));
  }
  // CIELAB (D65) of sRGB green and blue, L* 87.7347 and 32.3026, a* and b* scaled by L* / 100.
  const Triple green = flip::linearRgbToHuntLab({0, 1, 0}), blue = flip::linearRgbToHuntLab({0, 0, 1});
  CHECK(green[0] == Approx(87.7347).margin(0.01));
  CHECK(green[1] == Approx(-86.1827 * 0.877347).margin(0.02));
  CHECK(green[2] == Approx(83.1793 * 0.877347).margin(0.02));
  CHECK(blue[0] == Approx(32.3026).margin(0.01));
  CHECK(blue[1] == Approx(79.1967 * 0.323026).margin(0.02));
  CHECK(blue[2] == Approx(-107.8602 * 0.323026).margin(0.02));
  const Triple labWhite = flip::linearRgbToHuntLab({1, 1, 1});
  CHECK(labWhite[0] == Approx(100).margin(1e-3));
  CHECK(std::abs(labWhite[1]) < 1e-3);
  CHECK(std::abs(labWhite[2]) < 1e-3);
  CHECK(flip::hyab({10, 3, 4}, {4, 0, 0}) == Approx(6 + 5));
}

TEST_CASE("FLIP's colour error maps HyAB^0.7 to [0, 1] with 0.95 below 0.4 of green-to-blue", "[flip]") {
  const Triple green = flip::linearRgbToHuntLab({0, 1, 0}), blue = flip::linearRgbToHuntLab({0, 0, 1});
  const Triple black = flip::linearRgbToHuntLab({0, 0, 0}), white = flip::linearRgbToHuntLab({1, 1, 1});
  CHECK(flip::colourError(green, blue) == Approx(1).margin(1e-6));
  CHECK(flip::colourError(white, white) == 0);
  // c_max from the standard CIELAB values of green and blue.
  const double cMax = std::pow(std::abs(87.7347 - 32.3026) + std::hypot(-86.1827 * 0.877347 - 79.1967 * 0.323026,
                                                                        83.1793 * 0.877347 + 107.8602 * 0.323026),
                               0.7);
  const double blackWhite = std::pow(100.0, 0.7);  // above the knee at 0.4 c_max
  REQUIRE(blackWhite > 0.4 * cMax);
  CHECK(flip::colourError(black, white) == Approx(0.95 + (blackWhite - 0.4 * cMax) / (0.6 * cMax) * 0.05).margin(1e-4));
  // Below the knee, linear: 0.95 at 0.4 c_max.
  const Triple a = {50, 0, 0}, b = {50, 3, 4};  // HyAB 5
  CHECK(flip::colourError(a, b) == Approx(std::pow(5.0, 0.7) * 0.95 / (0.4 * cMax)).margin(1e-4));
}

TEST_CASE("FLIP's filters: contrast sensitivity per channel and feature kernels, normalised", "[flip]") {
  const double ppd = kFlipPixelsPerDegree;
  CHECK(ppd == Approx(67.0206).margin(1e-4));
  const flip::CsfFilters csf = flip::csfFilters(ppd);
  // ceil(3 sqrt(0.04 / (2 pi^2)) 67.02) = ceil(9.05)
  CHECK(csf.radius == 10);
  REQUIRE(csf.y.size() == 21);
  auto sum = [](const std::vector<float>& w) {
    double s = 0;
    for (const float v : w) s += v;
    return s;
  };
  CHECK(sum(csf.y) == Approx(1).margin(1e-6));
  CHECK(sum(csf.cx) == Approx(1).margin(1e-6));
  CHECK(sum(csf.cz1) * sum(csf.cz1) + sum(csf.cz2) * sum(csf.cz2) == Approx(1).margin(1e-6));
  const double pi2 = std::numbers::pi * std::numbers::pi, dx2 = 1 / (ppd * ppd);
  CHECK(csf.y[11] / csf.y[10] == Approx(std::exp(-pi2 * dx2 / 0.0047)).epsilon(1e-5));
  CHECK(csf.cx[11] / csf.cx[10] == Approx(std::exp(-pi2 * dx2 / 0.0053)).epsilon(1e-5));
  CHECK(csf.cz1[11] / csf.cz1[10] == Approx(std::exp(-pi2 * dx2 / 0.04)).epsilon(1e-5));
  CHECK(csf.cz2[11] / csf.cz2[10] == Approx(std::exp(-pi2 * dx2 / 0.025)).epsilon(1e-5));
  // The two Cz Gaussians' two-dimensional weights at the centre: 34.1 sqrt(pi / 0.04) to 13.5 sqrt(pi / 0.025).
  CHECK(csf.cz1[10] * csf.cz1[10] / (csf.cz2[10] * csf.cz2[10]) ==
        Approx(34.1 * std::sqrt(std::numbers::pi / 0.04) / (13.5 * std::sqrt(std::numbers::pi / 0.025))).epsilon(1e-5));

  const flip::FeatureFilters f = flip::featureFilters(ppd);
  const double sd = 0.5 * 0.082 * ppd;  // 2.75 pixels
  CHECK(f.radius == 9);
  REQUIRE(f.edge.size() == 19);
  CHECK(sum(f.gaussian) == Approx(1).margin(1e-6));
  CHECK(f.gaussian[10] / f.gaussian[9] == Approx(std::exp(-1 / (2 * sd * sd))).epsilon(1e-5));
  double edgePositive = 0, edgeNegative = 0, pointPositive = 0, pointNegative = 0;
  for (size_t k = 0; k < f.edge.size(); ++k) {
    (f.edge[k] > 0 ? edgePositive : edgeNegative) += f.edge[k];
    (f.point[k] > 0 ? pointPositive : pointNegative) += f.point[k];
    CHECK(f.edge[k] == Approx(-f.edge[18 - k]).margin(1e-7));
    CHECK(f.point[k] == Approx(f.point[18 - k]).margin(1e-7));
    const int x = int(k) - 9;
    CHECK((f.edge[k] > 0) == (x < 0));  // -x g(x)
    if (x != 0 && std::abs(std::abs(x) - sd) > 0.1) CHECK((f.point[k] > 0) == (std::abs(x) > sd));  // (x^2 / sd^2 - 1) g(x)
  }
  CHECK(edgePositive == Approx(1).margin(1e-6));
  CHECK(edgeNegative == Approx(-1).margin(1e-6));
  CHECK(pointPositive == Approx(1).margin(1e-6));
  CHECK(pointNegative == Approx(-1).margin(1e-6));
  // Fewer pixels per degree, narrower filters.
  CHECK(flip::csfFilters(10).radius == 2);
  CHECK(flip::featureFilters(10).radius == 2);
}

TEST_CASE("FLIP detects edges and points: a unit step has edge strength 1, a dot its kernel's centre", "[flip]") {
  const flip::FeatureFilters f = flip::featureFilters(kFlipPixelsPerDegree);
  const Image step = test::rgbImage(40, 24, [](int x, int) { return Rgb(x >= 20 ? 1.0f : 0.0f); });
  const Image strengths = flip::featureStrengths(step, kFlipPixelsPerDegree);
  for (int y = 0; y < 24; ++y) {
    CHECK(strengths.at(19, y, 0) == Approx(1).margin(1e-5));  // one side of the kernel, all of one sign
    CHECK(strengths.at(20, y, 0) == Approx(1).margin(1e-5));
    CHECK(strengths.at(19 - f.radius - 1, y, 0) == Approx(0).margin(1e-6));  // beyond the kernel: flat
    CHECK(strengths.at(20 + f.radius + 1, y, 0) == Approx(0).margin(1e-6));
  }
  const Image dot = test::rgbImage(31, 31, [](int x, int y) { return Rgb(x == 15 && y == 15 ? 1.0f : 0.0f); });
  const Image dotStrengths = flip::featureStrengths(dot, kFlipPixelsPerDegree);
  const double centre = std::abs(f.point[size_t(f.radius)]) * f.gaussian[size_t(f.radius)];
  CHECK(dotStrengths.at(15, 15, 1) == Approx(std::sqrt(2.0) * centre).epsilon(1e-5));
  CHECK(dotStrengths.at(15, 15, 0) == Approx(0).margin(1e-7));  // no gradient at the dot's centre
  // A flat image has no features.
  const Image flat = flip::featureStrengths(uniform(20, 20, {0.3f, 0.6f, 0.1f}), kFlipPixelsPerDegree);
  for (const float v : flat.pixels()) CHECK(v == Approx(0).margin(1e-6));
}

TEST_CASE("FLIP of identical images is 0, of flat images their colour error, and symmetric in LDR", "[flip]") {
  const Image image = structuredImage(7, 1, false);
  for (const bool hdr : {false, true}) {
    FlipOptions options;
    options.hdr = hdr;
    const FlipResult same = computeFlip(image, image, options);
    CHECK(same.mean == 0);
    CHECK(same.weightedMedian == 0);
    CHECK(*std::max_element(same.map.pixels().begin(), same.map.pixels().end()) == 0);
  }
  FlipOptions ldr;
  ldr.hdr = false;
  for (const auto& [a, b] : {std::pair{Triple{0.2f, 0.5f, 0.8f}, Triple{0.25f, 0.45f, 0.8f}},
                             {Triple{0, 0, 0}, Triple{1, 1, 1}}, {Triple{0.5f, 0.5f, 0.5f}, Triple{0.55f, 0.5f, 0.5f}}}) {
    const FlipResult r = computeFlip(uniform(30, 20, a), uniform(30, 20, b), ldr);
    const double expected = flip::colourError(flip::linearRgbToHuntLab(a), flip::linearRgbToHuntLab(b));
    for (const float v : r.map.pixels()) CHECK(v == Approx(expected).epsilon(1e-3));
  }
  const Image other = noisy(image, 0.1f, 8);
  const FlipResult ab = computeFlip(image, other, ldr), ba = computeFlip(other, image, ldr);
  for (size_t i = 0; i < ab.map.pixels().size(); ++i) CHECK(ab.map.pixels()[i] == Approx(ba.map.pixels()[i]).margin(1e-6));
}

TEST_CASE("LDR-FLIP equals the direct two-dimensional formulation of the paper", "[flip]") {
  const Image reference = structuredImage(11, 1, false);
  for (const double ppd : {kFlipPixelsPerDegree, 20.0}) {
    for (const float amplitude : {0.05f, 0.3f}) {
      const Image candidate = noisy(reference, amplitude, 12);
      FlipOptions options;
      options.hdr = false;
      options.pixelsPerDegree = ppd;
      const FlipResult result = computeFlip(candidate, reference, options);
      const std::vector<double> expected = directLdrFlip(candidate, reference, ppd);
      CAPTURE(ppd, amplitude);
      CHECK(largestDifference(result.map, expected) < 2e-5);
      double mean = 0;
      for (const double e : expected) mean += e;
      CHECK(result.mean == Approx(mean / double(expected.size())).margin(2e-6));
    }
  }
}

TEST_CASE("HDR-FLIP is each pixel's largest LDR-FLIP over the exposures, tone mapped by ACES", "[flip]") {
  const Image reference = structuredImage(21, 1, true), candidate = noisy(reference, 0.2f, 22);
  const FlipResult hdr = computeFlip(candidate, reference);
  REQUIRE(hdr.hdr);
  CHECK(hdr.exposures == int(std::max(2.0, std::ceil(hdr.stopExposure - hdr.startExposure))));
  std::vector<float> largest(hdr.map.pixels().size(), 0.0f);
  const double step = (hdr.stopExposure - hdr.startExposure) / (hdr.exposures - 1);
  FlipOptions ldr;
  ldr.hdr = false;
  for (int k = 0; k < hdr.exposures; ++k) {
    const float scale = float(std::exp2(hdr.startExposure + k * step));
    auto toneMapped = [scale](Image image) {
      for (float& v : image.pixels()) v = flip::acesToneMap(scale * v);
      return image;
    };
    const FlipResult at = computeFlip(toneMapped(candidate), toneMapped(reference), ldr);
    for (size_t i = 0; i < largest.size(); ++i) largest[i] = std::max(largest[i], at.map.pixels()[i]);
  }
  for (size_t i = 0; i < largest.size(); ++i) CHECK(hdr.map.pixels()[i] == Approx(largest[i]).margin(1e-6));
  // Exposure follows the reference: both images 8 times brighter, the same errors.
  auto brighter = [](Image image) {
    for (float& v : image.pixels()) v *= 8;
    return image;
  };
  const FlipResult scaled = computeFlip(brighter(candidate), brighter(reference));
  CHECK(scaled.startExposure == Approx(hdr.startExposure - 3).margin(1e-9));
  CHECK(scaled.stopExposure == Approx(hdr.stopExposure - 3).margin(1e-9));
  for (size_t i = 0; i < largest.size(); ++i) CHECK(scaled.map.pixels()[i] == Approx(hdr.map.pixels()[i]).margin(1e-4));
}

TEST_CASE("HDR-FLIP's exposure range puts the brightest pixel and the median at ACES 0.85", "[flip]") {
  CHECK(flip::acesToneMap(0) == 0);
  CHECK(flip::acesToneMap(1e6f) == 1);
  // Grey values (luminance = value): 39 at 0.1, 60 at 0.5, one at 5.
  const Image grey = test::rgbImage(10, 10, [](int x, int y) { return Rgb(y * 10 + x < 39 ? 0.1f : y * 10 + x < 99 ? 0.5f : 5.0f); });
  const std::array<double, 2> range = flip::exposureRange(grey);
  CHECK(flip::acesToneMap(float(5 * std::exp2(range[0]))) == Approx(0.85).margin(1e-5));
  CHECK(flip::acesToneMap(float(0.5 * std::exp2(range[1]))) == Approx(0.85).margin(1e-5));
  FlipOptions options;
  CHECK(computeFlip(grey, grey, options).exposures == 4);  // ceil(log2(10))
  // Mostly black: the median of the lit pixels (70 black, 29 at 0.25, one at 2).
  const Image dark = test::rgbImage(10, 10, [](int x, int y) { return Rgb(y * 10 + x < 70 ? 0.0f : y * 10 + x < 99 ? 0.25f : 2.0f); });
  const std::array<double, 2> darkRange = flip::exposureRange(dark);
  CHECK(flip::acesToneMap(float(0.25 * std::exp2(darkRange[1]))) == Approx(0.85).margin(1e-5));
  CHECK(flip::exposureRange(uniform(4, 4, {0, 0, 0})) == std::array<double, 2>{0, 0});
  // Given exposures are used; a start above the stop is refused.
  options.startExposure = -2;
  options.stopExposure = 3.5;
  const FlipResult given = computeFlip(grey, grey, options);
  CHECK(given.startExposure == -2);
  CHECK(given.exposures == 6);
  options.startExposure = 4;
  CHECK_THROWS_WITH(computeFlip(grey, grey, options), "FLIP's start exposure must not exceed its stop exposure");
}

TEST_CASE("FLIP's pooling: mean and error-weighted percentiles, and NaN pixels count as error 1", "[flip]") {
  const Image reference = structuredImage(31, 1, false);
  FlipOptions ldr;
  ldr.hdr = false;
  double previous = 0;
  for (const float amplitude : {0.02f, 0.08f, 0.3f}) {
    const FlipResult r = computeFlip(noisy(reference, amplitude, 32), reference, ldr);
    CHECK(r.mean > previous);  // more noise, more error
    previous = r.mean;
    std::vector<float> sorted = r.map.pixels();
    std::sort(sorted.begin(), sorted.end());
    double total = 0;
    for (const float e : sorted) total += e;
    for (const auto& [p, value] : {std::pair{0.25, r.weightedQuartile1}, {0.5, r.weightedMedian}, {0.75, r.weightedQuartile3}}) {
      double atOrBelow = 0, below = 0;
      for (const float e : sorted) {
        if (e <= value) atOrBelow += e;
        if (e < value) below += e;
      }
      CHECK(atOrBelow >= p * total);
      CHECK(below < p * total);
    }
    CHECK(r.weightedQuartile1 <= r.weightedMedian);
    CHECK(r.weightedMedian <= r.weightedQuartile3);
  }
  Image broken = reference;
  broken.at(5, 6, 1) = std::numeric_limits<float>::quiet_NaN();
  broken.at(30, 20, 0) = std::numeric_limits<float>::infinity();
  const FlipResult r = computeFlip(broken, reference);
  CHECK(r.nonFinite == 2);
  CHECK(r.map.at(5, 6, 0) == 1);
  CHECK(r.map.at(30, 20, 0) == 1);
  CHECK(std::isfinite(r.mean));
  CHECK_THROWS_WITH(computeFlip(reference, broken), "the reference has NaN or infinite values");
  CHECK_THROWS_WITH(computeFlip(reference, Image(48, 40, {"R", "G"})), "FLIP needs R, G and B channels; the reference has no B");
  CHECK_THROWS_WITH(computeFlip(reference, Image(4, 4, {"R", "G", "B"})), "FLIP needs images of one size: 48 x 40 against 4 x 4");
}

TEST_CASE("lucent compare --metric flip: LDR-FLIP of PNGs, HDR-FLIP of EXRs, its numbers and map", "[flip][cli]") {
  test::TempDir dir;
  const Image reference = structuredImage(41, 1, false), candidate = noisy(reference, 0.1f, 42);
  writePng(reference, (dir.path / "ref.png").string());
  writePng(candidate, (dir.path / "img.png").string());
  writeExr(reference, (dir.path / "ref.exr").string());
  writeExr(candidate, (dir.path / "img.exr").string());
  for (const bool hdr : {false, true}) {
    const std::string ext = hdr ? ".exr" : ".png";
    const std::string files = test::quoted((dir.path / ("img" + ext)).string()) + " " + test::quoted((dir.path / ("ref" + ext)).string());
    const test::CliRun run = test::runLucent("compare " + files + " --metric flip --ppd 40 --heatmap " + test::quoted((dir.path / "flip.png").string()));
    REQUIRE(run.status == 0);
    const nlohmann::json out = nlohmann::json::parse(run.output);
    FlipOptions options;
    options.hdr = hdr;
    options.pixelsPerDegree = 40;
    const FlipResult expected = computeFlip(readLinearImage((dir.path / ("img" + ext)).string()),
                                            readLinearImage((dir.path / ("ref" + ext)).string()), options);
    CHECK(out["flip"]["range"] == (hdr ? "hdr" : "ldr"));
    CHECK(out["value"].get<double>() == Approx(expected.mean).margin(1e-12));
    CHECK(out["flip"]["weighted_median"].get<double>() == Approx(expected.weightedMedian).margin(1e-12));
    CHECK(out["flip"]["weighted_quartiles"][1].get<double>() == Approx(expected.weightedQuartile3).margin(1e-12));
    CHECK(out["flip"]["pixels_per_degree"].get<double>() == 40);
    CHECK(out["flip"].contains("exposures") == hdr);
    CHECK(readImageHeader((dir.path / "flip.png").string()).width == 48);
    // --max-error applies to the mean.
    CHECK(test::runLucent("compare " + files + " --metric flip --ppd 40 --max-error " + std::to_string(expected.mean * 0.9)).status == 1);
  }
  const std::string files = test::quoted((dir.path / "img.exr").string()) + " " + test::quoted((dir.path / "ref.exr").string());
  const test::CliRun bad = test::runLucent("compare " + files + " --metric flip --ppd 0.5");
  CHECK(bad.status == 2);
  CHECK(bad.output.find("--ppd must lie in [1, 1000]") != std::string::npos);
  const test::CliRun without = test::runLucent("compare " + files + " --ppd 30");
  CHECK(without.status == 2);
  CHECK(without.output.find("--ppd needs --metric flip") != std::string::npos);
  const test::CliRun order = test::runLucent("compare " + files + " --metric flip --start-exposure 2 --stop-exposure 1");
  CHECK(order.status == 2);
  CHECK(order.output.find("--start-exposure must not exceed --stop-exposure") != std::string::npos);
}
