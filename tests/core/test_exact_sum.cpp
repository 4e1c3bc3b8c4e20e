// ExactSum: the film's order-independent sums.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "lucent/core/exact_sum.h"
#include "lucent/pipeline/film.h"

using namespace lucent;

namespace {

// Floats of both signs over 2^-60 .. 2^60: far more range than a double sum keeps exactly.
std::vector<float> wideTerms(size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> exponent(-60.0f, 60.0f), mantissa(1.0f, 2.0f);
  std::vector<float> terms(n);
  for (float& t : terms) t = std::ldexp(mantissa(rng), int(exponent(rng))) * (rng() & 1 ? 1.0f : -1.0f);
  return terms;
}

}  // namespace

TEST_CASE("ExactSum does not depend on the order or grouping of its terms", "[exact_sum]") {
  std::vector<float> terms = wideTerms(10000, 1);
  ExactSum forward;
  for (float t : terms) forward.add(t);
  // Doubles summed in another order differ: the test's terms are not a trivial case.
  double doubleForward = 0, doubleReverse = 0;
  for (float t : terms) doubleForward += t;
  for (auto it = terms.rbegin(); it != terms.rend(); ++it) doubleReverse += *it;
  CHECK(doubleForward != doubleReverse);

  std::mt19937 rng(2);
  for (int trial = 0; trial < 5; ++trial) {
    std::shuffle(terms.begin(), terms.end(), rng);
    // Split into partial sums at random points, then merged.
    ExactSum merged, part;
    for (size_t i = 0; i < terms.size(); ++i) {
      part.add(terms[i]);
      if (rng() % 97 == 0) merged.add(part), part = ExactSum();
    }
    merged.add(part);
    CHECK(merged == forward);
    CHECK(merged.value() == forward.value());
  }
}

TEST_CASE("ExactSum's value is the sum to double precision", "[exact_sum]") {
  // Terms of 2^-40 .. 2^40 over a sum of at most 2^60: the value is within a double's rounding of
  // the long double sum of the terms sorted by magnitude (the accurate way to sum them in floating point).
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> exponent(-40.0f, 40.0f);
  std::vector<float> terms(5000);
  for (float& t : terms) t = std::ldexp(1.0f + float(rng() % 1000) / 1000.0f, int(exponent(rng)));
  ExactSum sum;
  for (float t : terms) sum.add(t);
  std::sort(terms.begin(), terms.end());
  long double reference = 0;
  for (float t : terms) reference += t;
  CHECK(std::abs(double(sum.value() - reference)) <= 4e-16 * double(reference));

  // Exact cases: integers, halves, a negative total, cancellation to zero.
  ExactSum small;
  for (int i = 0; i < 1000; ++i) small.add(0.5f);
  CHECK(small.value() == 500.0);
  small.add(-1000.0f);
  CHECK(small.value() == -500.0);
  small.add(500.0f);
  CHECK(small.value() == 0.0);
  CHECK(small == ExactSum());
}

TEST_CASE("ExactSum keeps terms down to 2^-96 and holds 2^24 of its largest terms", "[exact_sum]") {
  ExactSum tiny;
  tiny.add(0x1p-96f);
  CHECK(tiny.value() == 0x1p-96);
  tiny.add(0x1p-97f);  // below the last bit: dropped
  CHECK(tiny.value() == 0x1p-96);
  tiny.add(std::numeric_limits<float>::denorm_min());
  CHECK(tiny.value() == 0x1p-96);

  ExactSum large;
  for (int i = 0; i < 1 << 24; ++i) large.add(ExactSum::kMaxTerm);
  CHECK(large.value() == 0x1p94);
  for (int i = 0; i < 1 << 24; ++i) large.add(-ExactSum::kMaxTerm);
  CHECK(large.value() == 0.0);
  CHECK(ExactSum::accepts(ExactSum::kMaxTerm));
  CHECK_FALSE(ExactSum::accepts(std::nextafter(ExactSum::kMaxTerm, 1e30f)));
  CHECK_FALSE(ExactSum::accepts(std::numeric_limits<float>::quiet_NaN()));
  CHECK_FALSE(ExactSum::accepts(std::numeric_limits<float>::infinity()));
}

TEST_CASE("Films of parts of an image add up to the film of the whole", "[exact_sum][film]") {
  // Samples of a 6 x 4 image into one film, and into two crops that split it, each over two
  // sample ranges: the merged film is the single film, sum for sum.
  const int w = 6, h = 4;
  auto sample = [](int x, int y, int s) {
    const float v = std::ldexp(1.0f + float((x * 7 + y * 13 + s * 5) % 17) / 17.0f, (x + y + s) % 50 - 25);
    return Rgb(v, v * 0.5f, v * 3.0f);
  };
  Film whole(w, h, Film::Sums::PerSample, {true, false});
  const PixelRect left{0, 0, 2, h}, right{2, 0, w, h};
  Film merged(w, h, Film::Sums::PerSample, {true, false});
  for (const PixelRect& crop : {left, right})
    for (const auto& [first, count] : {std::pair{0, 5}, std::pair{5, 3}}) {
      Film part(w, h, crop, Film::Sums::PerSample, {true, false});
      for (int y = crop.y0; y < crop.y1; ++y)
        for (int x = crop.x0; x < crop.x1; ++x) {
          const uint64_t pixel = uint64_t(y) * w + x;
          for (int s = first; s < first + count; ++s)
            part.addSample(pixel, sample(x, y, s), sample(y, x, s), Rgb(0.5f), Vec3(0, 0, 1), float(s));
          part.setTaken(pixel, uint32_t(count));
        }
      merged.add(part);
    }
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int s = 0; s < 8; ++s)
        whole.addSample(uint64_t(y) * w + x, sample(x, y, s), sample(y, x, s), Rgb(0.5f), Vec3(0, 0, 1), float(s));
  CHECK(std::equal(whole.pixelSums().begin(), whole.pixelSums().end(), merged.pixelSums().begin()));
  CHECK(std::equal(whole.validSamples().begin(), whole.validSamples().end(), merged.validSamples().begin()));
  for (uint32_t taken : merged.samplesTaken()) CHECK(taken == 8);
  const Image a = whole.image(), b = merged.image();
  CHECK(std::equal(a.pixels().begin(), a.pixels().end(), b.pixels().begin()));
  // A crop's image is the crop's pixels.
  Film crop(w, h, right, Film::Sums::PerSample, {false, false});
  crop.addSample(uint64_t(1) * w + 3, Rgb(2.0f), Rgb(1.0f), Rgb(), Vec3(), 0);
  const Image cropped = crop.image();
  CHECK(cropped.width() == 4);
  CHECK(cropped.at(1, 1, 0) == 3.0f);
  CHECK_THROWS_AS(Film(w, h, PixelRect{4, 0, 7, 4}, Film::Sums::PerSample, {}), std::invalid_argument);
  CHECK_THROWS_AS(whole.add(Film(w, h, left, Film::Sums::PerPart, {true, false})), std::invalid_argument);
}
