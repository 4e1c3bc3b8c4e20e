// Statistical tests of the sampling core (rng.h, sampling.h, distribution.h, Frame): a chi-square test of
// every sampler (tests/chi2.h), each paired with a negative control that a wrong sampler is rejected.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <vector>

#include "chi2.h"
#include "lucent/core/distribution.h"
#include "lucent/core/lane_clones.h"
#include "lucent/core/path_sampler.h"
#include "lucent/core/rng.h"
#include "lucent/core/sampling.h"
#include "lucent/core/sobol.h"

using namespace lucent;
using chi2::DirectionSample;
using chi2::IndexSample;
using chi2::PointSample;

namespace {

// The number of passing chi-square tests below (negative controls excluded). With the Sidak-corrected
// level, all of them pass with probability 0.99 for correct samplers, whatever the seeds.
constexpr int kChi2Tests = 21;
const double kAlpha = chi2::sidak(0.01, kChi2Tests);

std::vector<float> randomWeights(size_t n, uint64_t seed) {
  Rng rng(seed);
  std::vector<float> w(n);
  for (float& x : w) x = rng.uniform() < 0.2f ? 0.0f : 0.1f + rng.uniform();
  return w;
}

// Samples a direction sampler and claims the given pdf for it.
template <class Warp, class Pdf>
auto directionSampler(Warp warp, Pdf pdf) {
  return [=](Rng& rng) {
    const Vec3 d = warp(rng.uniform2());
    return DirectionSample{d, pdf(d)};
  };
}

}  // namespace

TEST_CASE("chi2: incomplete gamma function matches closed forms", "[sampling][chi2]") {
  for (double x : {1e-3, 0.5, 1.0, 2.5, 7.0, 30.0, 120.0}) {
    CHECK(chi2::gammaQ(1, x) == Approx(std::exp(-x)).epsilon(1e-12));
    CHECK(chi2::gammaQ(0.5, x) == Approx(std::erfc(std::sqrt(x))).epsilon(1e-10));
    // Q(n, x) = e^-x sum_{k<n} x^k / k! for integer n.
    for (int n : {2, 5, 40, 100}) {
      double term = 1, sum = 0;
      for (int k = 0; k < n; ++k) sum += term, term *= x / (k + 1);
      CHECK(chi2::gammaQ(n, x) == Approx(std::exp(-x) * sum).epsilon(1e-10));
    }
  }
  CHECK(chi2::chi2PValue(0, 10) == 1);
  CHECK(chi2::chi2PValue(3.0, 2) == Approx(std::exp(-1.5)).epsilon(1e-12));
}

TEST_CASE("chi2: pooling and zero-probability cells", "[sampling][chi2]") {
  chi2::Result r;
  const std::vector<double> expected{1, 2, 3, 100, 200, 0};
  chi2::pooledChi2(std::vector<double>{1, 2, 3, 100, 200, 0}, expected, 5, r);
  CHECK(r.statistic == 0);
  CHECK(r.dof == 2);  // {1,2,3} pooled, then 100 and 200
  CHECK(r.error.empty());
  chi2::Result stray;
  chi2::pooledChi2(std::vector<double>{1, 2, 3, 100, 200, 1}, expected, 5, stray);
  CHECK_FALSE(stray.error.empty());
}

TEST_CASE("chi2: samplers that fail where their pdf is zero", "[sampling][chi2]") {
  auto upperPdf = [](Vec3 d) { return d.z > 0 ? kUniformSpherePdf : 0.0f; };
  auto failingBelow = [](float zFail) {
    return [=](Rng& rng) {
      const Vec3 d = sampleUniformSphere(rng.uniform2());
      return DirectionSample{d, d.z > zFail ? kUniformSpherePdf : 0.0f};
    };
  };
  CHECK_CHI2_PASS(chi2::testSphere(failingBelow(0), upperPdf, {.mass = 0.5}));
  CHECK_CHI2_PASS(chi2::testSphere(failingBelow(0), upperPdf, {.mass = std::nullopt}));
  // Negative control: fails on 55% of the sphere instead of 50%.
  CHECK_CHI2_REJECT(chi2::testSphere(failingBelow(0.1f), upperPdf, {.mass = std::nullopt}));
  // A pdf that does not integrate to the claimed mass is an error.
  CHECK_FALSE(chi2::testSphere(failingBelow(0), upperPdf).passed(0));
}

TEST_CASE("sinCosQuarterPi agrees with sin and cos in double to about an ulp", "[sampling]") {
  double worstSin = 0, worstCos = 0;
  for (int i = -100000; i <= 100000; ++i) {
    const float x = float(kPi / 4 * i / 100000.0);
    const Vec2 sc = sinCosQuarterPi(x);
    worstSin = std::max(worstSin, std::abs(sc.x - std::sin(double(x))));
    worstCos = std::max(worstCos, std::abs(sc.y - std::cos(double(x))));
  }
  // A float ulp below 1 is 6e-8; rounding in the nested products costs at most a few.
  CHECK(worstSin < 1.5e-7);
  CHECK(worstCos < 1.5e-7);
}

TEST_CASE("sampleConcentricDisk maps the square's border to the unit circle, sector by sector", "[sampling]") {
  for (int i = 0; i <= 1000; ++i) {
    const float t = i / 1000.0f;
    for (const Vec2 u : {Vec2{t, 0}, Vec2{t, 1}, Vec2{0, t}, Vec2{1, t}}) {
      const Vec2 d = sampleConcentricDisk(u);
      CHECK(d.x * d.x + d.y * d.y == Approx(1.0f).margin(3e-7));
      // Same quadrant as the square's point (the map preserves the sign of each coordinate).
      CHECK(d.x * (2 * u.x - 1) >= 0);
      CHECK(d.y * (2 * u.y - 1) >= 0);
    }
  }
  CHECK(sampleConcentricDisk({0.5f, 0.5f}).x == 0.0f);
}

TEST_CASE("powerHeuristic: a^2 / (a^2 + b^2), the two weights summing to 1, at any densities", "[sampling]") {
  CHECK(powerHeuristic(1.0f, 0.0f) == 1.0f);
  CHECK(powerHeuristic(0.0f, 1.0f) == 0.0f);
  CHECK(powerHeuristic(0.0f, 0.0f) == 0.0f);
  CHECK(powerHeuristic(3.0f, 1.0f) == Approx(0.9));
  CHECK(powerHeuristic(1.0f, 3.0f) == Approx(0.1));
  // Densities whose squares overflow a float (a near-mirror lobe), and infinite ones.
  for (const float scale : {1.0f, 1e10f, 1e20f, 1e30f, 1e-30f}) {
    INFO("scale " << scale);
    CHECK(powerHeuristic(3 * scale, scale) == Approx(0.9));
    CHECK(powerHeuristic(scale, 3 * scale) + powerHeuristic(3 * scale, scale) == Approx(1.0));
  }
  const float inf = std::numeric_limits<float>::infinity();
  CHECK(powerHeuristic(inf, 1e30f) == 1.0f);
  CHECK(powerHeuristic(1e30f, inf) == 0.0f);
  CHECK(powerHeuristic(inf, inf) == 0.5f);
}

TEST_CASE("sampleCosineHemisphere", "[sampling]") {
  SECTION("around +z") {
    auto pdf = [](Vec3 d) { return cosineHemispherePdf(d.z); };
    CHECK_CHI2_PASS(chi2::testSphere(directionSampler(sampleCosineHemisphere, pdf), pdf, {.zMin = 0}));
  }

  SECTION("around a normal near -z, through Frame") {
    const Vec3 n = normalize(Vec3(1e-3f, -2e-3f, -1));
    const Frame frame(n);
    auto pdfN = [=](Vec3 d) { return cosineHemispherePdf(dot(d, n)); };
    auto warp = [=](Vec2 u) { return frame.toWorld(sampleCosineHemisphere(u)); };
    CHECK_CHI2_PASS(chi2::testSphere(directionSampler(warp, pdfN), pdfN, {.zMin = 0, .axis = n}));
  }
  SECTION("negative control: checked against the uniform hemisphere") {
    auto uniform = [](Vec3 d) { return d.z > 0 ? 0.5f * kInvPi : 0.0f; };
    CHECK_CHI2_REJECT(chi2::testSphere(directionSampler(sampleCosineHemisphere, uniform), uniform, {.zMin = 0}));
  }
}

TEST_CASE("sampleUniformSphere", "[sampling]") {
  auto pdf = [](Vec3) { return kUniformSpherePdf; };
  SECTION("uniform") { CHECK_CHI2_PASS(chi2::testSphere(directionSampler(sampleUniformSphere, pdf), pdf)); }
  SECTION("negative control: uniform in theta instead of cos(theta)") {
    auto warp = [](Vec2 u) {
      const float theta = kPi * u.x, phi = 2 * kPi * u.y;
      return Vec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
    };
    CHECK_CHI2_REJECT(chi2::testSphere(directionSampler(warp, pdf), pdf));
  }
}

TEST_CASE("sampleUniformCone", "[sampling]") {
  auto conePdf = [](float cosMax) { return [=](Vec3 d) { return d.z >= cosMax ? uniformConePdf(cosMax) : 0.0f; }; };
  auto coneWarp = [](float cosMax) { return [=](Vec2 u) { return sampleUniformCone(u, cosMax); }; };
  SECTION("cosMax 0.9 and 0.3") {
    for (float cosMax : {0.9f, 0.3f}) {
      INFO("cosMax = " << cosMax);
      // The cap puts the cone's edge inside a theta bin, two thirds of the way down.
      const chi2::Options opt{.seed = cosMax > 0.5f ? 1u : 2u, .zMin = 1 - 1.5 * (1 - cosMax)};
      CHECK_CHI2_PASS(chi2::testSphere(directionSampler(coneWarp(cosMax), conePdf(cosMax)), conePdf(cosMax), opt));
    }
  }
  SECTION("negative control: a cone of cosMax 0.92 checked as 0.9") {
    const chi2::Options opt{.zMin = 0.85};
    CHECK_CHI2_REJECT(chi2::testSphere(directionSampler(coneWarp(0.92f), conePdf(0.9f)), conePdf(0.9f), opt));
  }
}

TEST_CASE("sampleUniformTriangle", "[sampling]") {
  // Barycentrics (b1, b2) are uniform over the half b1 + b2 <= 1 of the unit square, density 2.
  auto pdf = [](Vec2 b) { return b.x + b.y <= 1 ? 2.0f : 0.0f; };
  SECTION("uniform") {
    auto sampler = [&](Rng& rng) { return PointSample{sampleUniformTriangle(rng.uniform2()), 2.0f}; };
    CHECK_CHI2_PASS(chi2::testSquare(sampler, pdf));
  }

  SECTION("negative control: b1 = u1, b2 = (1 - u1) u2 crowds the b1 = 1 corner") {
    auto wrong = [](Rng& rng) {
      const Vec2 u = rng.uniform2();
      return PointSample{{u.x, (1 - u.x) * u.y}, 2.0f};
    };
    CHECK_CHI2_REJECT(chi2::testSquare(wrong, pdf));
  }
}

TEST_CASE("samplePhongLobe", "[sampling]") {
  auto pdf = [](float n) { return [=](Vec3 d) { return phongLobePdf(d.z, n); }; };
  auto warp = [](float n) { return [=](Vec2 u) { return samplePhongLobe(u, n); }; };
  // Bins in the cap holding all but 1e-3 of the lobe (cos^(n+1) = 1e-3), so that they resolve it.
  auto capFor = [](float n) { return chi2::Options{.zMin = std::pow(1e-3, 1.0 / (n + 1))}; };
  SECTION("exponents 1, 10, 100, 1000") {
    for (float n : {1.0f, 10.0f, 100.0f, 1000.0f}) {
      INFO("exponent " << n);
      CHECK_CHI2_PASS(chi2::testSphere(directionSampler(warp(n), pdf(n)), pdf(n), capFor(n)));
    }
  }
  SECTION("negative controls: exponent 10 checked as 12, 1000 as 1050") {
    CHECK_CHI2_REJECT(chi2::testSphere(directionSampler(warp(10), pdf(12)), pdf(12), capFor(12)));
    CHECK_CHI2_REJECT(chi2::testSphere(directionSampler(warp(1000), pdf(1050)), pdf(1050), capFor(1000)));
  }
}

TEST_CASE("Distribution1D::sampleDiscrete", "[sampling][distribution]") {
  const std::vector<float> weights = [] {
    auto w = randomWeights(37, 11);
    w.front() = w.back() = w[20] = w[21] = 0;  // zero bins at both ends and in a run
    return w;
  }();
  auto test = [](const std::vector<float>& w, const Distribution1D& dist, uint64_t seed) {
    double sum = 0;
    for (float x : w) sum += x;
    auto pmf = [&](uint32_t i) { return sum > 0 ? float(w[i] / sum) : 1.0f / float(w.size()); };
    auto sampler = [&](Rng& rng) {
      float p = 0;
      const uint32_t i = dist.sampleDiscrete(rng.uniform(), &p);
      return IndexSample{i, p};
    };
    return chi2::testDiscrete(sampler, pmf, uint32_t(w.size()), {.seed = seed});
  };
  SECTION("with zero-weight bins") {
    const Distribution1D dist(weights);
    CHECK_CHI2_PASS(test(weights, dist, 1));
    for (uint32_t i = 0; i < dist.size(); ++i) CHECK(dist.pmf(i) == Approx(weights[i] / dist.total()));
  }

  SECTION("all-zero weights become uniform") {
    const std::vector<float> zeros(9, 0.0f);
    const Distribution1D uniform(zeros);
    CHECK(uniform.total() == 0);
    CHECK_CHI2_PASS(test(zeros, uniform, 2));
  }
  SECTION("negative control: the heaviest weight 5% too high") {
    auto perturbed = weights;
    *std::max_element(perturbed.begin(), perturbed.end()) *= 1.05f;
    const Distribution1D wrong(perturbed);
    // The claimed pmf of `wrong` differs only at index 7; what matters is the histogram.
    CHECK_CHI2_REJECT(test(weights, wrong, 3));
  }
  SECTION("invalid weights are rejected") {
    CHECK_THROWS(Distribution1D(std::vector<float>{}));
    CHECK_THROWS(Distribution1D(std::vector<float>{1, -1}));
    CHECK_THROWS(Distribution1D(std::vector<float>{1, NAN}));
    CHECK_THROWS(Distribution1D(std::vector<float>{1, INFINITY}));
  }
}

TEST_CASE("Distribution1D::pick is the first bin whose upper CDF value exceeds u, on the 2^-24 grid",
          "[sampling][distribution]") {
  // The reference: std::upper_bound over the normalized running sums, clamped to the last bin, for
  // every u a sampler can draw (k 2^-24) next to each CDF value, and a finer u below a cell's
  // upper end, which picks what its cell's u does.
  for (const uint32_t n : {1u, 2u, 3u, 5u, 8u, 13u, 37u}) {
    auto w = randomWeights(n, 100 + n);
    if (n > 3) w[1] = w[2] = 0;  // a run of zero-weight bins
    const Distribution1D dist(w);
    std::vector<double> cdf(n + 1, 0.0);
    for (uint32_t i = 0; i < n; ++i) cdf[i + 1] = cdf[i] + w[i];
    for (auto& c : cdf) c /= cdf[n];
    cdf[n] = 1.0;
    std::vector<float> us = {0.0f, 1 - 0x1p-24f};
    for (uint32_t i = 0; i <= n; ++i)  // every boundary and its neighbours on the grid
      for (int64_t k = int64_t(std::floor(cdf[i] * 0x1p24)) - 1, last = k + 3; k < last; ++k)
        if (k >= 0 && k < int64_t(Distribution1D::kCells)) us.push_back(float(k) * 0x1p-24f);
    Rng rng(n);
    for (int k = 0; k < 1000; ++k) us.push_back(rng.uniform());
    for (const float u : us) {
      const auto it = std::upper_bound(cdf.begin() + 1, cdf.end(), double(u));
      const auto expected = uint32_t(std::min<ptrdiff_t>(it - cdf.begin() - 1, n - 1));
      REQUIRE(dist.pick(u) == expected);
      if (dist.total() > 0) REQUIRE(dist.weight(dist.pick(u)) > 0);
      if (u > 0) REQUIRE(dist.pick(std::nextafter(u + 0x1p-24f, 0.0f)) == expected);
    }
  }
}

TEST_CASE("Distribution1D: the pmf is the probability of the pick over the 2^-24 grid, however small a weight",
          "[sampling][distribution]") {
  // Weights down to 1e-12 of the heaviest, where a bin is narrower than a cell of u's grid: every
  // u a sampler can draw, k 2^-24, is picked once, and each bin's count must be its pmf x 2^24
  // exactly (weight / total would be an estimator's divisor that its samples do not follow).
  const std::vector<float> weights = {1.0f, 1e-9f, 3e-8f, 0.0f, 0.5f, 1e-7f, 2.0f, 1e-12f, 4e-6f};
  const auto n = uint32_t(weights.size());
  double total = 0;
  for (const float w : weights) total += w;
  auto counts = [&](const Distribution1D& dist) {
    std::vector<uint64_t> count(n, 0);
    for (uint32_t k = 0; k < Distribution1D::kCells; ++k) ++count[dist.pick(float(k) * 0x1p-24f)];
    return count;
  };
  for (const bool owned : {false, true}) {
    INFO((owned ? "bins 1 and 7 own a cell" : "no bin owns a cell"));
    std::vector<uint8_t> ownCell(n, 0);
    if (owned) ownCell[1] = ownCell[7] = ownCell[3] = 1;  // bin 3 weighs nothing: it still gets none
    const Distribution1D dist(weights, owned ? std::span<const uint8_t>(ownCell) : std::span<const uint8_t>());
    const std::vector<uint64_t> count = counts(dist);
    const uint32_t owners = owned ? 2 : 0;
    double sum = 0;
    for (uint32_t i = 0; i < n; ++i) {
      INFO("bin " << i << " weight " << weights[i] << ": " << count[i] << " cells, pmf " << dist.pmf(i));
      CHECK(double(count[i]) == double(dist.pmf(i)) * 0x1p24);
      CHECK(count[i] == dist.cellCount(i));
      // About its share: off by less than a cell and the owners' cells.
      CHECK(std::abs(double(dist.pmf(i)) - weights[i] / total) <= (1 + owners) * 0x1p-24);
      sum += dist.pmf(i);
      // Within a bin, u's remapped values are its cells' starts over the bin: uniform over [0, 1).
      if (count[i] > 0 && count[i] < 64) {
        std::set<float> remapped;
        for (uint32_t k = dist.firstCell(i); k < dist.firstCell(i) + dist.cellCount(i); ++k)
          remapped.insert(dist.remap(i, float(k) * 0x1p-24f));
        CHECK(remapped.size() == count[i]);
        CHECK(*remapped.begin() == 0.0f);
        CHECK(*remapped.rbegin() == Approx(double(count[i] - 1) / count[i]));
      }
    }
    CHECK(sum == 1.0);
    CHECK(count[3] == 0);
    if (owned) {
      CHECK(count[1] >= 1);
      CHECK(count[7] >= 1);
    } else {
      // Negative control: the 1e-12 bin is narrower than a cell, so never picked, and its pmf says so;
      // its share of the weights, 2.9e-13, would not.
      CHECK(count[7] == 0);
      CHECK(dist.pmf(7) == 0.0f);
      CHECK(double(count[7]) != weights[7] / total * 0x1p24);
    }
  }
  SECTION("impossible flags are refused") {
    CHECK_THROWS(Distribution1D(weights, std::vector<uint8_t>(n - 1, 1)));
  }
}

TEST_CASE("Distribution1D::sampleContinuous", "[sampling][distribution]") {
  // 50 histogram cells over 37 bins: most bin edges fall inside cells.
  auto test = [](const std::vector<float>& w, const Distribution1D& dist, uint64_t seed) {
    double sum = 0;
    for (float x : w) sum += x;
    const auto n = uint32_t(w.size());
    auto pdf = [&, sum](Vec2 p) {
      const uint32_t i = std::min(uint32_t(p.x * n), n - 1);
      return sum > 0 ? float(w[i] * n / sum) : 1.0f;
    };
    uint64_t wrongBins = 0;
    auto sampler = [&](Rng& rng) {
      float p = 0;
      uint32_t bin = 0;
      const float x = dist.sampleContinuous(rng.uniform(), &p, &bin);
      wrongBins += bin != std::min(uint32_t(x * n), n - 1);
      return PointSample{{x, rng.uniform()}, p};
    };
    const chi2::Result r = chi2::testSquare(sampler, pdf, {.seed = seed, .xBins = 50, .yBins = 1});
    CHECK(wrongBins == 0);
    return r;
  };
  const std::vector<float> weights = [] {
    auto w = randomWeights(37, 12);
    w.front() = w.back() = w[20] = w[21] = 0;
    return w;
  }();
  SECTION("with zero-weight bins") { CHECK_CHI2_PASS(test(weights, Distribution1D(weights), 4)); }

  SECTION("all-zero weights become uniform") {
    const std::vector<float> zeros(37, 0.0f);
    CHECK_CHI2_PASS(test(zeros, Distribution1D(zeros), 5));
  }
  SECTION("negative control: the heaviest weight 10% too high") {
    auto perturbed = weights;
    *std::max_element(perturbed.begin(), perturbed.end()) *= 1.1f;
    CHECK_CHI2_REJECT(test(weights, Distribution1D(perturbed), 6));
  }
}

TEST_CASE("Distribution1D::sampleContinuous stays in the bin it picked", "[sampling][distribution]") {
  // Many bins, every other one empty: rounding x up into the next bin would give a zero pdf.
  std::vector<float> weights(1000, 0.0f);
  for (size_t i = 0; i < weights.size(); i += 2) weights[i] = 1;
  const Distribution1D dist(weights);
  Rng rng(7);
  uint64_t strays = 0;
  for (int k = 0; k < 1'000'000; ++k) {
    float pdf;
    uint32_t bin;
    const float x = dist.sampleContinuous(rng.uniform(), &pdf, &bin);
    strays += !(pdf > 0) || bin != uint32_t(x * weights.size()) || dist.pdfContinuous(x) != pdf;
  }
  CHECK(strays == 0);
}

TEST_CASE("Distribution2D", "[sampling][distribution]") {
  constexpr uint32_t nu = 13, nv = 9;
  std::vector<float> weights = randomWeights(nu * nv, 13);
  for (uint32_t u = 0; u < nu; ++u) weights[0 * nu + u] = weights[4 * nu + u] = 0;  // zero rows
  double sum = 0;
  for (float x : weights) sum += x;
  auto pdf = [&](Vec2 p) {
    const uint32_t u = std::min(uint32_t(p.x * nu), nu - 1), v = std::min(uint32_t(p.y * nv), nv - 1);
    return float(weights[v * nu + u] * nu * nv / sum);
  };
  const Distribution2D dist(weights, nu, nv);
  auto sampler = [&](const Distribution2D& d) {
    return [&](Rng& rng) {
      PointSample s;
      s.point = d.sample(rng.uniform2(), &s.pdf);
      return s;
    };
  };
  SECTION("with zero rows") {
    CHECK_CHI2_PASS(chi2::testSquare(sampler(dist), pdf));
    Rng rng(14);
    for (int i = 0; i < 1000; ++i) {
      const Vec2 p = rng.uniform2();
      CHECK(dist.pdf(p) == Approx(pdf(p)).epsilon(1e-5));
    }
    CHECK_THROWS(Distribution2D(weights, nu, nv + 1));
  }

  SECTION("negative control: one row 10% too heavy") {
    auto perturbed = weights;
    for (uint32_t u = 0; u < nu; ++u) perturbed[2 * nu + u] *= 1.1f;
    const Distribution2D wrong(perturbed, nu, nv);
    auto claimingPdf = [&](Rng& rng) {
      PointSample s = sampler(wrong)(rng);
      s.pdf = pdf(s.point);
      return s;
    };
    CHECK_CHI2_REJECT(chi2::testSquare(claimingPdf, pdf));
  }
}

TEST_CASE("latitude-longitude mapping", "[sampling]") {
  SECTION("directionToLatLong inverts latLongToDirection") {
    std::vector<float> vs;
    for (int j = 1; j < 1024; ++j) vs.push_back(j / 1024.0f);
    for (float p = 1e-6f; p < 1e-2f; p *= 1.5f) vs.insert(vs.end(), {p, 1 - p});  // near the poles
    for (float v : vs)
      for (int k = 0; k < 64; ++k) {
        const Vec2 uv{(k + 0.37f) / 64, v};
        const Vec3 d = latLongToDirection(uv);
        CHECK(length(d) == Approx(1).epsilon(1e-6));
        const Vec2 back = directionToLatLong(d);
        const float du = std::abs(back.x - uv.x);
        INFO("uv = (" << uv.x << ", " << uv.y << "), back = (" << back.x << ", " << back.y << ")");
        CHECK(std::min(du, 1 - du) < 1e-5f);  // u is periodic
        CHECK(std::abs(back.y - uv.y) < 1e-5f);
      }
    // v = 0 is +y, u = 0 is -z, u = 1/4 is +x.
    CHECK(latLongToDirection({0.3f, 0}).y == 1);
    CHECK(latLongToDirection({0, 0.5f}).z == Approx(-1));
    CHECK(latLongToDirection({0.25f, 0.5f}).x == Approx(1));
  }

  SECTION("directions sampled from a Distribution2D over the map") {
    constexpr uint32_t nu = 24, nv = 12;
    std::vector<float> weights = randomWeights(nu * nv, 15);
    for (uint32_t u = 0; u < nu; ++u) weights[5 * nu + u] = 0;
    double sum = 0;
    for (float x : weights) sum += x;
    const Distribution2D dist(weights, nu, nv);
    // Solid-angle density: the map's density over [0,1)^2 divided by the Jacobian 2 pi^2 sin(theta).
    auto pdf = [&](Vec3 d) {
      const Vec2 uv = directionToLatLong(d);
      const uint32_t u = std::min(uint32_t(uv.x * nu), nu - 1), v = std::min(uint32_t(uv.y * nv), nv - 1);
      const double sinTheta = std::sqrt(double(d.x) * d.x + double(d.z) * d.z);
      return sinTheta > 0 ? float(weights[v * nu + u] * nu * nv / sum / (2 * kPi * kPi * sinTheta)) : 0.0f;
    };
    auto sampler = [&](bool jacobian) {
      return [&, jacobian](Rng& rng) {
        float pdfUV;
        const Vec2 uv = dist.sample(rng.uniform2(), &pdfUV);
        const Vec3 d = latLongToDirection(uv);
        const float sinTheta = std::sin(kPi * uv.y);
        return DirectionSample{d, sinTheta > 0 ? pdfUV / (2 * kPi * kPi * (jacobian ? sinTheta : 1)) : 0};
      };
    };
    // Binning around the map's pole (+y) puts the pdf's 1/sin(theta) pole where the harness's
    // integration cancels it.
    const chi2::Options opt{.axis = {0, 1, 0}};
    CHECK_CHI2_PASS(chi2::testSphere(sampler(true), pdf, opt));

    // Negative control: the sampler's density without the sin(theta) Jacobian.
    auto noJacobian = [&](Vec3 d) {
      const double sinTheta = std::sqrt(double(d.x) * d.x + double(d.z) * d.z);
      return float(pdf(d) * sinTheta);
    };
    CHECK_CHI2_REJECT(chi2::testSphere(sampler(false), noJacobian, opt));
  }
}

TEST_CASE("Rng", "[sampling][rng]") {
  SECTION("uniform() is in [0, 1) and reaches both ends") {
    Rng rng(21);
    float lo = 1, hi = 0;
    for (int i = 0; i < 1'000'000; ++i) {
      const float u = rng.uniform();
      lo = std::min(lo, u), hi = std::max(hi, u);
    }
    CHECK(lo >= 0);
    CHECK(hi < 1);
    CHECK(lo < 1e-5f);
    CHECK(hi > 1 - 1e-5f);
    CHECK(float(0xffffffffu >> 8) * 0x1p-24f < 1);  // the largest value uniform() can return
  }
  SECTION("keys select distinct streams; equal keys give equal streams") {
    std::set<std::vector<uint32_t>> streams;
    int count = 0;
    for (uint64_t seed : {0, 1, 2})
      for (uint64_t a : {0, 1, 2, 1000})
        for (uint64_t b : {0, 1, 2, 1000}) {
          Rng rng(seed, a, b), same(seed, a, b);
          std::vector<uint32_t> first(4);
          for (auto& x : first) {
            x = rng.next();
            CHECK(same.next() == x);
          }
          streams.insert(first);
          ++count;
        }
    CHECK(streams.size() == size_t(count));
  }
  SECTION("uniform2() is uniform on the square") {
    auto sampler = [](Rng& rng) { return PointSample{rng.uniform2(), 1.0f}; };
    CHECK_CHI2_PASS(chi2::testSquare(sampler, [](Vec2) { return 1.0f; }, {.xBins = 32, .yBins = 32}));
  }
  SECTION("first numbers of neighbouring keys are independent") {
    // Pixels and photons seed one generator each from consecutive keys.
    uint64_t key = 0;
    auto sampler = [&](Rng&) {
      const Vec2 p{Rng(22, key).uniform(), Rng(22, key + 1).uniform()};
      ++key;
      return PointSample{p, 1.0f};
    };
    CHECK_CHI2_PASS(chi2::testSquare(sampler, [](Vec2) { return 1.0f; }, {.xBins = 32, .yBins = 32}));
  }
  SECTION("below(n) is uniform") {
    constexpr uint32_t n = 37;
    auto pmf = [](uint32_t) { return 1.0f / n; };
    auto sampler = [](Rng& rng) { return IndexSample{rng.below(n), 1.0f / n}; };
    CHECK_CHI2_PASS(chi2::testDiscrete(sampler, pmf, n));
    // Negative control: 8 random bits spread over 37 values, 6 or 7 of 256 each.
    auto coarse = [](Rng& rng) { return IndexSample{((rng.next() >> 24) * n) >> 8, 1.0f / n}; };
    CHECK_CHI2_REJECT(chi2::testDiscrete(coarse, pmf, n));
  }
}

TEST_CASE("isFinite is false exactly when a component is infinite or NaN", "[math]") {
  const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN();
  const float big = std::numeric_limits<float>::max(), tiny = std::numeric_limits<float>::denorm_min();
  for (float ok : {0.0f, -0.0f, 1.0f, -big, big, tiny, -tiny})
    for (int axis = 0; axis < 3; ++axis) {
      Vec3 v{1, -2, 3};
      v[axis] = ok;
      CHECK(isFinite(v));
      CHECK(isFinite(Rgb(v.x, v.y, v.z)));
      for (float bad : {inf, -inf, nan}) {
        Vec3 w = v;
        w[(axis + 1) % 3] = bad;
        CHECK_FALSE(isFinite(w));
        CHECK_FALSE(isFinite(Rgb(w.x, w.y, w.z)));
      }
    }
}

TEST_CASE("Frame is orthonormal and inverts itself", "[sampling][frame]") {
  std::vector<Vec3> normals{{0, 0, 1}, {0, 0, -1}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {-1, 0, 0}, {1, 0, -0.0f}};
  for (Vec3 n : {Vec3(1e-4f, 0, -1), Vec3(0, 1e-6f, -1), Vec3(1e-3f, -2e-3f, -1), Vec3(-1e-7f, 1e-7f, -1),
                 Vec3(1, 1, 1), Vec3(1e-4f, 0, 1), Vec3(1, 0, -1e-7f)})
    normals.push_back(normalize(n));
  Rng rng(31);
  for (int i = 0; i < 2000; ++i) normals.push_back(sampleUniformSphere(rng.uniform2()));
  // Directions within about 1e-3 radians of -z.
  for (int i = 0; i < 2000; ++i) normals.push_back(-sampleUniformCone(rng.uniform2(), 1 - 1e-6f));

  for (Vec3 n : normals) {
    const Frame f(n);
    INFO("n = (" << n.x << ", " << n.y << ", " << n.z << ")");
    CHECK(length(f.s) == Approx(1).margin(1e-5));
    CHECK(length(f.t) == Approx(1).margin(1e-5));
    CHECK(std::abs(dot(f.s, f.t)) < 1e-5f);
    CHECK(std::abs(dot(f.s, f.n)) < 1e-5f);
    CHECK(std::abs(dot(f.t, f.n)) < 1e-5f);
    CHECK(length(cross(f.s, f.t) - f.n) < 1e-5f);  // right-handed
    const Vec3 v = sampleUniformSphere(rng.uniform2()) * 3.0f;
    CHECK(length(f.toWorld(f.toLocal(v)) - v) < 1e-5f * 3);
    CHECK(length(f.toLocal(f.n) - Vec3(0, 0, 1)) < 1e-5f);
  }
}

TEST_CASE("stratifiedSample2D puts one sample in each cell of its grid", "[sampling]") {
  Rng rng(31);
  for (uint32_t n : {1u, 2u, 4u, 7u, 16u, 30u, 4096u}) {
    const auto nx = static_cast<uint32_t>(std::sqrt(double(n))), ny = n / nx;
    std::set<std::pair<uint32_t, uint32_t>> cells;
    for (uint32_t i = 0; i < n; ++i) {
      const Vec2 u = rng.uniform2();
      const Vec2 s = stratifiedSample2D(i, n, u);
      INFO("n " << n << ", sample " << i);
      REQUIRE((s.x >= 0 && s.x < 1 && s.y >= 0 && s.y < 1));
      if (i < nx * ny) {
        const auto cell = std::pair{uint32_t(s.x * nx), uint32_t(s.y * ny)};
        REQUIRE(cell == std::pair{i % nx, i / nx});
        cells.insert(cell);
        // Uniform within the cell: the jitter is the offset in it.
        REQUIRE(s.x * nx - float(i % nx) == Approx(u.x).margin(1e-5));
        REQUIRE(s.y * ny - float(i / nx) == Approx(u.y).margin(1e-5));
      } else {
        REQUIRE((s.x == u.x && s.y == u.y));  // the remainder is uniform over the square
      }
    }
    REQUIRE(cells.size() == size_t(nx) * ny);
  }
  // The last cell's upper edge stays below 1.
  const Vec2 s = stratifiedSample2D(3, 4, {0x1.fffffep-1f, 0x1.fffffep-1f});
  REQUIRE((s.x < 1 && s.y < 1));
}

TEST_CASE("Sobol points: every elementary interval of 2^-m holds its share, scrambled or not", "[sampling]") {
  // The first three dimensions of Sobol's sequence are a (1, 3)-sequence in base 2: the first 2^m
  // points put exactly two in every box of volume 2^(1 - m) whose sides are powers of two, and each
  // dimension alone one in every interval of 2^-m. Owen scrambling keeps both, for any seed.
  for (const uint32_t seed : {0u, 1u, 0xdeadbeefu}) {
    const bool scrambled = seed != 0;
    auto coordinate = [&](uint32_t i, int d) {
      return scrambled ? owenScramble(sobolBits(i, d), seed * 7919u + uint32_t(d)) : sobolBits(i, d);
    };
    for (int m = 1; m <= 10; ++m) {
      const uint32_t n = 1u << m;
      for (int d = 0; d < kSobolDimensions; ++d) {
        std::set<uint32_t> cells;
        for (uint32_t i = 0; i < n; ++i) cells.insert(coordinate(i, d) >> (32 - m));
        INFO("seed " << seed << ", m " << m << ", dimension " << d);
        REQUIRE(cells.size() == n);
      }
      for (int a = 0; a < m; ++a)
        for (int b = 0; a + b < m; ++b) {
          const int c = m - 1 - a - b;
          std::vector<int> count(size_t(1) << (m - 1), 0);
          auto top = [](uint32_t v, int bits) { return bits == 0 ? 0u : v >> (32 - bits); };
          for (uint32_t i = 0; i < n; ++i) {
            const uint32_t box = top(coordinate(i, 0), a) << (b + c) | top(coordinate(i, 1), b) << c | top(coordinate(i, 2), c);
            ++count[box];
          }
          INFO("seed " << seed << ", m " << m << ", box 2^-" << a << " x 2^-" << b << " x 2^-" << c);
          REQUIRE(std::all_of(count.begin(), count.end(), [](int k) { return k == 2; }));
        }
    }
  }
  // Negative control: independent random points miss that (some box of 2^-5 x 2^-5 holds 3 or more
  // of 1,024 points).
  Rng rng(5);
  std::vector<int> count(1024, 0);
  for (int i = 0; i < 1024; ++i) ++count[size_t(uint32_t(rng.uniform() * 32) * 32 + uint32_t(rng.uniform() * 32))];
  REQUIRE(*std::max_element(count.begin(), count.end()) >= 3);
  // sobolSample: in [0, 1), and the same 24 bits as the scrambled integer.
  for (uint32_t i = 0; i < 4096; ++i) {
    const float u = sobolSample(i, 2, 99);
    REQUIRE(u >= 0.0f);
    REQUIRE(u < 1.0f);
    REQUIRE(u == float(owenScramble(sobolBits(i, 2), 99) >> 8) * 0x1p-24f);
  }
}

TEST_CASE("shuffledSobolPair is the Owen-scrambled pair of the Owen-shuffled index", "[sampling][sobol]") {
  Rng rng(41);
  for (int k = 0; k < 20000; ++k) {
    const uint32_t index = rng.next(), shuffle = rng.next(), sx = rng.next(), sy = rng.next();
    const uint32_t shuffled = owenScramble(index, shuffle);
    const std::array<uint32_t, 2> pair = shuffledSobolPair(index, shuffle, sx, sy);
    REQUIRE(pair[0] == owenScramble(sobolBits(shuffled, 0), sx));
    REQUIRE(pair[1] == owenScramble(sobolBits(shuffled, 1), sy));
    // The same point's third and fourth dimensions.
    const std::array<uint32_t, 2> second = shuffledSobolPair(index, shuffle, sx, sy, true);
    REQUIRE(second[0] == owenScramble(sobolBits(shuffled, 2), sx));
    REQUIRE(second[1] == owenScramble(sobolBits(shuffled, 3), sy));
  }
}

namespace {
// The numbers of one (bounce, use) for a pixel's samples [0, n).
std::vector<Vec2> pixelPairs(uint64_t seed, uint64_t pixel, int bounce, SampleUse use, uint32_t n) {
  std::vector<Vec2> points;
  for (uint32_t i = 0; i < n; ++i) {
    PathSampler s(SamplerKind::Sobol, seed, pixel, i);
    points.push_back(use == SampleUse::LightPoint || use == SampleUse::BsdfDirection
                         ? s.uniform2(bounce, use)
                         : Vec2{s.uniform(bounce, use), s.uniform(bounce, SampleUse(uint32_t(use) ^ 1u))});
  }
  return points;
}
// Whether the first n = 2^m points are a (t, m, s)-net in base 2: 2^t of them in every box of
// volume 2^(t - m) whose sides are powers of two (s = 2 and t = 0: one in every elementary box).
template <size_t S>
bool isNet(const std::vector<std::array<float, S>>& points, int m, int t) {
  std::array<int, S> sides{};  // the box's sides 2^-sides[j], summing to m - t
  auto each = [&](auto&& self, size_t j, int left) -> bool {
    if (j + 1 == S) {
      sides[j] = left;
      std::map<std::array<uint32_t, S>, int> boxes;
      for (size_t i = 0; i < (size_t(1) << m); ++i) {
        std::array<uint32_t, S> box;
        for (size_t d = 0; d < S; ++d) box[d] = uint32_t(points[i][d] * float(1u << sides[d]));
        ++boxes[box];
      }
      return boxes.size() == (size_t(1) << (m - t)) &&
             std::all_of(boxes.begin(), boxes.end(), [&](const auto& box) { return box.second == 1 << t; });
    }
    for (sides[j] = 0; sides[j] <= left; ++sides[j])
      if (!self(self, j + 1, left - sides[j])) return false;
    return true;
  };
  return each(each, 0, m - t);
}
// Whether the first n = 2^m points put one in every box 2^-a x 2^-(m - a).
bool stratified(const std::vector<Vec2>& points, int m) {
  std::vector<std::array<float, 2>> pairs;
  for (const Vec2 p : points) pairs.push_back({p.x, p.y});
  return isNet(pairs, m, 0);
}
}  // namespace

TEST_CASE("PathSampler (Sobol): a light point is stratified with the direction the path arrived along", "[sampling][sobol]") {
  // A bounce's light point and the direction its path arrived along (the position in the pixel at
  // the first bounce, the bounce before's BSDF direction later) are one 4D Sobol sequence: a
  // pixel's first 2^m samples put 8 points in every box of volume 2^(3 - m), and the light point
  // alone 4 in every box of area 2^(2 - m) (the t-values of Sobol's dimensions 0 to 3 and 2, 3).
  auto sets = [](uint64_t pixel, int bounce, std::vector<std::array<float, 4>>& joint, std::vector<std::array<float, 2>>& light) {
    joint.clear(), light.clear();
    for (uint32_t i = 0; i < 1024; ++i) {
      PathSampler s(SamplerKind::Sobol, 3, pixel, i);
      const Vec2 arrival = bounce == 0 ? s.camera() : s.uniform2(bounce - 1, SampleUse::BsdfDirection);
      const Vec2 point = s.uniform2(bounce, SampleUse::LightPoint);
      joint.push_back({arrival.x, arrival.y, point.x, point.y});
      light.push_back({point.x, point.y});
    }
  };
  std::vector<std::array<float, 4>> joint;
  std::vector<std::array<float, 2>> light;
  for (const uint64_t pixel : {0ull, 17ull, 123456ull})
    for (const int bounce : {0, 1, 7}) {
      sets(pixel, bounce, joint, light);
      for (int m = 3; m <= 10; ++m) {
        INFO("pixel " << pixel << ", bounce " << bounce << ", 2^" << m << " samples");
        REQUIRE(isNet(joint, m, 3));
        REQUIRE(isNet(light, m, 2));
      }
    }
  // Negative control: a light point with a shuffle of its own (padded pairs) is not stratified with
  // the arrival: some box of 2^-10 x ... holds other than 8 of 1,024 points.
  joint.clear();
  for (uint32_t i = 0; i < 1024; ++i) {
    const std::array<uint32_t, 2> a = shuffledSobolPair(i, 11, 12, 13), b = shuffledSobolPair(i, 21, 22, 23, true);
    joint.push_back({float(a[0] >> 8) * 0x1p-24f, float(a[1] >> 8) * 0x1p-24f, float(b[0] >> 8) * 0x1p-24f,
                     float(b[1] >> 8) * 0x1p-24f});
  }
  REQUIRE_FALSE(isNet(joint, 10, 3));
}

TEST_CASE("PathSampler (Sobol): a pixel's first 2^m samples are stratified in every other purpose's pair", "[sampling][sobol]") {
  // Every other pair of dimensions (the pixel position, and per bounce the roulette with the lobe
  // and the BSDF direction) of a pixel's first 2^m samples holds one point in every elementary box
  // of area 2^-m: a (0, 2)-sequence in base 2.
  for (const uint64_t pixel : {0ull, 17ull, 123456ull})
    for (const int bounce : {0, 1, 7})
      for (const SampleUse use : {SampleUse::Roulette, SampleUse::BsdfDirection}) {
        const std::vector<Vec2> points = pixelPairs(3, pixel, bounce, use, 1024);
        for (int m = 0; m <= 10; ++m) {
          INFO("pixel " << pixel << ", bounce " << bounce << ", use " << uint32_t(use) << ", 2^" << m << " samples");
          REQUIRE(stratified(points, m));
        }
      }
  std::vector<Vec2> camera;
  for (uint32_t i = 0; i < 256; ++i) camera.push_back(PathSampler(SamplerKind::Sobol, 3, 99, i).camera());
  REQUIRE(stratified(camera, 8));
  // Negative control: independent numbers are not stratified.
  std::vector<Vec2> independent;
  for (uint32_t i = 0; i < 256; ++i) independent.push_back(PathSampler(SamplerKind::Independent, 3, 99, i).camera());
  REQUIRE_FALSE(stratified(independent, 8));
}

TEST_CASE("PathSampler (Sobol): pairs, pixels and seeds are independent of one another", "[sampling][sobol][chi2]") {
  // Chi-square of the joint distribution of two numbers that must be independent uniforms: two
  // purposes of one sample, one purpose of neighbouring pixels, one purpose under two seeds. A
  // scramble that ignored the pixel, the seed or the pair would put all points on one curve.
  auto pairOf = [](auto&& numbers) {
    return [=](Rng& rng) {
      const uint64_t pixel = rng.next();
      const uint32_t sample = rng.below(4096);
      return PointSample{numbers(pixel, sample), 1.0f};
    };
  };
  auto sobol = [](uint64_t seed, uint64_t pixel, uint32_t sample) { return PathSampler(SamplerKind::Sobol, seed, pixel, sample); };
  SECTION("two purposes of one sample") {
    CHECK_CHI2_PASS(chi2::testSquare(pairOf([&](uint64_t p, uint32_t i) {
      PathSampler s = sobol(1, p, i);
      return Vec2{s.uniform2(0, SampleUse::LightPoint).x, s.uniform2(0, SampleUse::BsdfDirection).x};
    }), [](Vec2) { return 1.0f; }));
    CHECK_CHI2_PASS(chi2::testSquare(pairOf([&](uint64_t p, uint32_t i) {
      PathSampler s = sobol(1, p, i);
      return Vec2{s.camera().y, s.uniform(1, SampleUse::Roulette)};
    }), [](Vec2) { return 1.0f; }));
  }
  SECTION("neighbouring pixels, and two seeds") {
    CHECK_CHI2_PASS(chi2::testSquare(pairOf([&](uint64_t p, uint32_t i) {
      return Vec2{sobol(1, p, i).uniform2(2, SampleUse::BsdfDirection).y, sobol(1, p + 1, i).uniform2(2, SampleUse::BsdfDirection).y};
    }), [](Vec2) { return 1.0f; }));
    CHECK_CHI2_PASS(chi2::testSquare(pairOf([&](uint64_t p, uint32_t i) {
      return Vec2{sobol(1, p, i).uniform(0, SampleUse::Lobe), sobol(2, p, i).uniform(0, SampleUse::Lobe)};
    }), [](Vec2) { return 1.0f; }));
  }
  SECTION("negative control: two pairs keyed alike (the pair left out of their seeds)") {
    CHECK_CHI2_REJECT(chi2::testSquare(pairOf([&](uint64_t p, uint32_t i) {
      const uint32_t seed = uint32_t(p);
      const std::array<uint32_t, 2> v = shuffledSobolPair(i, seed, seed * 3, seed * 5);
      const std::array<uint32_t, 2> w = shuffledSobolPair(i, seed, seed * 3, seed * 7);
      return Vec2{float(v[0] >> 8) * 0x1p-24f, float(w[0] >> 8) * 0x1p-24f};
    }), [](Vec2) { return 1.0f; }));
  }
}

TEST_CASE("PathSampler (Sobol): unbiased, and a smooth integrand's variance far below independent sampling's",
          "[sampling][sobol]") {
  // f(u, v) = exp(u) sin(pi v) over [0,1)^2: (e - 1) 2 / pi. Per pixel, the mean of 64 samples of
  // one pair; over 4,096 pixels (independent scrambles), the mean of those estimates within four of
  // its standard errors of the integral, and their variance. Independent sampling's variance of a
  // 64-sample mean is Var f / 64 = 0.0116 / 64; a (0, 2)-sequence's, for an f this smooth, falls as
  // n^-3 (Owen 1997): at 64 samples well below a tenth of it. Pixels that shared one scramble
  // would give one estimate 4,096 times (variance 0 but the mean off by its error).
  const double exact = (std::exp(1.0) - 1.0) * 2.0 / kPi;
  auto f = [](Vec2 p) { return std::exp(double(p.x)) * std::sin(kPi * double(p.y)); };
  const double varF = (std::exp(2.0) - 1.0) / 2.0 * 0.5 - exact * exact;
  for (const SampleUse use : {SampleUse::LightPoint, SampleUse::BsdfDirection, SampleUse::Roulette}) {
    std::vector<double> estimates;
    for (uint64_t pixel = 0; pixel < 4096; ++pixel) {
      double sum = 0;
      for (const Vec2 p : pixelPairs(11, pixel, 1, use, 64)) sum += f(p);
      estimates.push_back(sum / 64);
    }
    double mean = 0, var = 0;
    for (double e : estimates) mean += e;
    mean /= double(estimates.size());
    for (double e : estimates) var += (e - mean) * (e - mean);
    var /= double(estimates.size() - 1);
    INFO("use " << uint32_t(use) << ": mean " << mean << " (exact " << exact << "), variance " << var
                << " (independent: " << varF / 64 << ")");
    REQUIRE(var > 0);
    REQUIRE(std::abs(mean - exact) < 4 * std::sqrt(var / double(estimates.size())));
    REQUIRE(var < 0.1 * varF / 64);
  }
}

TEST_CASE("PathSampler (independent): the keyed Rng's numbers, in the order asked", "[sampling]") {
  PathSampler s(SamplerKind::Independent, 5, 77, 3);
  Rng rng(5, 77, 3);
  const Vec2 camera = s.camera(), first = rng.uniform2();
  REQUIRE((camera.x == first.x && camera.y == first.y));
  for (int k = 0; k < 100; ++k) {
    const Vec2 a = s.uniform2(k, SampleUse::BsdfDirection), b = rng.uniform2();
    REQUIRE((a.x == b.x && a.y == b.y));
    REQUIRE(s.uniform(k, SampleUse::Roulette) == rng.uniform());
  }
}

TEST_CASE("PathSampler (Sobol): pairs and camera pairs drawn in lanes are the sampler's, with every instruction set", "[sampling][sobol][isa]") {
  // Samplers of several pixels and samples, the pairs of many purposes and bounces, in one call of
  // each lane version; each must equal what the sampler itself gives.
  const LaneIsa saved = laneIsa();
  std::vector<PathSampler> samplers;
  std::vector<uint64_t> keys;
  std::vector<uint32_t> index, dimension;
  for (uint64_t pixel = 0; pixel < 7; ++pixel)
    for (uint64_t sample : {0ull, 1ull, 5ull, 1000ull, 123456789ull})
      for (int bounce = 0; bounce < 12; ++bounce)
        for (const SampleUse use : {SampleUse::Roulette, SampleUse::LightPoint, SampleUse::BsdfDirection}) {
          samplers.emplace_back(SamplerKind::Sobol, 11, pixel, sample);
          keys.push_back(samplers.back().pixelKey()), index.push_back(samplers.back().index());
          dimension.push_back(PathSampler::dimension(bounce, use));
        }
  for (const LaneIsa isa : supportedLaneIsas()) {
    setLaneIsa(isa);
    std::vector<float> x(keys.size(), -1), y(keys.size(), -1);
    sobolPairs(keys.data(), index.data(), dimension.data(), uint32_t(keys.size()), x.data(), y.data());
    auto check = [&](size_t k) {
      const uint32_t d = dimension[k];
      const int bounce = int((d - kCameraDimensions) / kBounceDimensions);
      const SampleUse use = SampleUse((d - kCameraDimensions) % kBounceDimensions);
      const Vec2 expected = samplers[k].uniform2(bounce, use);
      CAPTURE(laneIsaName(isa), k);
      REQUIRE((x[k] == expected.x && y[k] == expected.y));
    };
    for (size_t k = 0; k < keys.size(); ++k) check(k);
    // A batch without light points (drawn without their lookups): the first 36 pairs' others.
    std::vector<uint32_t> others;
    for (uint32_t k = 0; k < 108; ++k)
      if (!PathSampler::isLightPoint(dimension[k])) others.push_back(k);
    REQUIRE(others.size() == 72);
    std::fill(x.begin(), x.end(), -1.0f), std::fill(y.begin(), y.end(), -1.0f);
    std::vector<uint64_t> otherKeys;
    std::vector<uint32_t> otherIndex, otherDimension;
    for (const uint32_t k : others)
      otherKeys.push_back(keys[k]), otherIndex.push_back(index[k]), otherDimension.push_back(dimension[k]);
    std::vector<float> ox(others.size()), oy(others.size());
    sobolPairs(otherKeys.data(), otherIndex.data(), otherDimension.data(), uint32_t(others.size()), ox.data(), oy.data());
    for (size_t j = 0; j < others.size(); ++j) x[others[j]] = ox[j], y[others[j]] = oy[j];
    for (const uint32_t k : others) check(k);
    // The camera's pairs with the pixels' keys, 37 samples (a vector's tail).
    std::vector<uint64_t> pixel, sample, cameraKey(37);
    for (uint64_t k = 0; k < 37; ++k) pixel.push_back(mix64(k) % 100000), sample.push_back(k * 977 % 4099);
    std::vector<float> cx(37), cy(37);
    sobolCameraPairs(23, pixel.data(), sample.data(), 37, cameraKey.data(), cx.data(), cy.data());
    for (size_t k = 0; k < 37; ++k) {
      PathSampler s(SamplerKind::Sobol, 23, pixel[k], sample[k]);
      const Vec2 expected = s.camera();
      CAPTURE(laneIsaName(isa), k);
      REQUIRE(cameraKey[k] == s.pixelKey());
      REQUIRE((cx[k] == expected.x && cy[k] == expected.y));
    }
  }
  setLaneIsa(saved);
}
