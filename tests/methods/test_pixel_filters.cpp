// Pixel filters sampled by filter importance: the sampled positions follow each filter, and a
// render of a slanted edge and of a small square light, seen straight on against black, matches
// the analytic filtered image (each pixel the filter's integral over what emits) within its noise,
// for the path tracer and for the methods that share the eye paths.
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "chi2.h"
#include "lucent/core/pixel_filter.h"
#include "lucent/methods/methods.h"
#include "lucent/methods/pathtrace.h"
#include "lucent/scene/camera.h"
#include "lucent/trace/visibility.h"
#include "test_scenes.h"

using namespace lucent;

namespace {

const PixelFilterKind kKinds[] = {PixelFilterKind::Box, PixelFilterKind::Tent, PixelFilterKind::Gaussian,
                                  PixelFilterKind::BlackmanHarris, PixelFilterKind::Mitchell};

// The analytic filter's integral from a to b over its whole integral (or its magnitude's over the
// magnitude's), from its running integral on a grid of 200,000 intervals (trapezoids; independent
// of the sampler's table).
class FilterShare {
 public:
  FilterShare(PixelFilterKind kind, double radius, bool magnitude = false) : radius_(radius), running_(kSteps + 1, 0.0) {
    const double h = 2 * radius / kSteps;
    auto f = [&](double x) {
      const double v = filterValue1D(kind, radius, x);
      return magnitude ? std::abs(v) : v;
    };
    for (int i = 0; i < kSteps; ++i)
      running_[size_t(i) + 1] = running_[size_t(i)] + 0.5 * h * (f(-radius + i * h) + f(-radius + (i + 1) * h));
    total_ = running_.back();
    for (double& v : running_) v /= total_;
  }
  double total() const { return total_; }
  double operator()(double a, double b) const { return at(b) - at(a); }

 private:
  static constexpr int kSteps = 200000;
  double at(double x) const {
    const double t = std::clamp((x + radius_) / (2 * radius_), 0.0, 1.0) * kSteps;
    const size_t i = std::min(size_t(t), size_t(kSteps - 1));
    return running_[i] + (t - double(i)) * (running_[i + 1] - running_[i]);
  }
  double radius_, total_ = 1;
  std::vector<double> running_;
};

}  // namespace

TEST_CASE("Pixel filters: sampled positions follow the filter, the weights average to 1", "[filter]") {
  for (PixelFilterKind kind : kKinds) {
    const PixelFilter filter({kind, 0});
    INFO(pixelFilterName(kind));
    CHECK(filter.radius() == defaultFilterRadius(kind));
    // The weighted count in 40 cells of x against the filter's share of each: chi-square on the
    // magnitudes, and the signed weights' mean 1 (the filter normalized).
    const int cells = 40, samples = 200000;
    std::vector<double> observed(cells, 0.0), expected(cells, 0.0);
    std::mt19937_64 rng(uint64_t(kind) + 1);
    std::uniform_real_distribution<float> uniform(0.0f, 1.0f);
    double weights = 0;
    const double r = filter.radius();
    for (int i = 0; i < samples; ++i) {
      float w = 0;
      const Vec2 p = filter.position({uniform(rng), uniform(rng)}, w);
      weights += w;
      const double x = p.x - 0.5;
      REQUIRE(std::abs(x) <= r + 1e-6);
      observed[size_t(std::min(cells - 1, int((x + r) / (2 * r) * cells)))] += 1;
    }
    double absolute = 0;
    const FilterShare share(kind, r, true);
    for (int c = 0; c < cells; ++c) {
      const double a = -r + 2 * r * c / cells, b = a + 2 * r / cells;
      expected[size_t(c)] = share(a, b);
      absolute += expected[size_t(c)];
    }
    for (double& e : expected) e *= samples / absolute;
    chi2::Result result;
    chi2::pooledChi2(observed, expected, 5, result);
    INFO(result.error << " chi-square p " << result.pValue);
    CHECK(result.passed(1e-3));
    CHECK(weights / samples == Approx(1.0).margin(kind == PixelFilterKind::Mitchell ? 0.01 : 1e-6));
  }
  CHECK_THROWS(PixelFilter({PixelFilterKind::Tent, 20}));
  // A box wider than the pixel is a filter of its own, not the pixel's box.
  CHECK(PixelFilter({PixelFilterKind::Box, 0}).isBox());
  CHECK_FALSE(PixelFilter({PixelFilterKind::Box, 1.5}).isBox());
  float w = 0;
  CHECK(PixelFilter({PixelFilterKind::Box, 1.5}).position({0.0f, 1.0f}, w).x == Approx(-1.0).margin(1e-3));
}

TEST_CASE("Pixel filters: a slanted edge and a small square light render as their analytic filtered images",
          "[filter][pathtrace]") {
  // Seen straight on from 1 unit, 27.7 pixels a unit: a large triangle whose one edge in view
  // runs at about 14 degrees from the vertical, radiance 1; and a square of 0.3 x 0.3 pixels,
  // radiance 40, off the pixel grid. Black around them, nothing reflects.
  constexpr int side = 32;
  Scene scene;
  Material emitter;
  emitter.kd = Rgb(0.0f);
  emitter.ke = Rgb(1.0f);
  const uint32_t edge = test::addMaterial(scene, emitter, "edge");
  emitter.ke = Rgb(40.0f);
  const uint32_t small = test::addMaterial(scene, emitter, "square");
  scene.camera = test::testCamera({0, 0, 0}, {0, 0, -1}, side, side, 60.0f);
  const PinholeCamera camera(scene.camera);
  // The world position at image position (px, py) on the plane z = -1.
  auto world = [&](double px, double py) {
    const Ray r = camera.generate(float(px), float(py));
    return r.direction * (-1.0f / r.direction.z);
  };
  const Vec3 top = world(14.0, -100.0), bottom = world(14.0 + 0.25 * 232.0, 132.0);  // the edge's ends
  const Vec3 far = world(-200.0, 16.0);
  // The square in front of the edge's plane, at depth 0.9.
  auto nearer = [&](double px, double py) { return world(px, py) * 0.9f; };
  // One triangle, counter-clockwise seen from the camera (its normal towards +z).
  for (const Vec3& v : {top, far, bottom}) {
    scene.positions.push_back(v);
    scene.normals.push_back({0, 0, 0});
    scene.texcoords.push_back({0, 0});
  }
  scene.indices.insert(scene.indices.end(), {0u, 1u, 2u});
  scene.materialIds.push_back(edge);
  const double cx = 23.37, cy = 9.71, half = 0.15;  // the square's centre and half side, in pixels
  test::addQuad(scene, nearer(cx - half, cy + half), nearer(cx + half, cy + half), nearer(cx + half, cy - half),
                nearer(cx - half, cy - half), small);
  finalizeScene(scene);
  const Visibility vis(scene);
  // Image position of the edge's line: x = x0 + slope (y - y0).
  const Vec3 a = camera.project(top), b = camera.project(bottom);
  const double slope = double(b.x - a.x) / double(b.y - a.y);
  // The largest |z| of an image's pixels against the analytic filtered image.
  auto largestZ = [&](const Image& image, PixelFilterKind kind, int spp) {
    const double r = defaultFilterRadius(kind);
    const FilterShare share(kind, r), magnitude(kind, r, true);
    // A sample's weight: integral |f| / integral f squared (the two axes), negative in negative lobes.
    const double weight = std::pow(magnitude.total() / share.total(), 2);
    double worst = 0;
    int worstX = 0, worstY = 0;
    for (int py = 0; py < side; ++py)
      for (int px = 0; px < side; ++px) {
        // A sample brings 40 from the square, 1 from the edge's side of the line elsewhere, 0
        // beyond it, times its weight. The edge: along y the share of each thin row, along x the
        // filter's share left of the line in that row.
        auto shares = [&](const FilterShare& s) {
          const int rows = 400;
          double edgeShare = 0;
          for (int k = 0; k < rows; ++k) {
            const double v0 = -r + 2 * r * k / rows, v1 = v0 + 2 * r / rows, v = 0.5 * (v0 + v1);
            const double lineX = double(a.x) + slope * (py + 0.5 + v - double(a.y));
            edgeShare += s(v0, v1) * s(-r - 1, lineX - (px + 0.5));
          }
          const double squareShare = s(cx - half - (px + 0.5), cx + half - (px + 0.5)) *
                                     s(cy - half - (py + 0.5), cy + half - (py + 0.5));
          return std::pair{edgeShare, squareShare};
        };
        const auto [edgeShare, squareShare] = shares(share);
        const double expected = edgeShare + (40.0 - 1.0) * squareShare;
        // The variance of the pixel's mean from the sample's second moment, on the magnitude.
        const auto [edgeMagnitude, squareMagnitude] = shares(magnitude);
        const double second = weight * weight * (1600.0 * squareMagnitude + edgeMagnitude - squareMagnitude);
        const double variance = (second - expected * expected) / spp;
        const double value = image.at(px, py, 0);
        const double z = (value - expected) / std::sqrt(std::max(variance, 0.0) + 1e-12);
        if (std::abs(z) > worst) worst = std::abs(z), worstX = px, worstY = py;
      }
    INFO("largest |z| " << worst << " at " << worstX << ", " << worstY);
    return worst;
  };
  // 1,024 pixels: |z| beyond 4.4 has probability 1e-5 each under the normal distribution.
  for (PixelFilterKind kind : kKinds) {
    INFO("pt, " << pixelFilterName(kind));
    PathTraceOptions opt;
    opt.common.spp = 2048;
    opt.common.seed = 7;
    opt.common.pixelFilter = kind;
    opt.sampler = SamplerKind::Independent;
    CHECK(largestZ(renderPathTraced(scene, vis, opt).image, kind, opt.common.spp) < 4.4);
  }
  // The methods that share the eye paths sample the same filter.
  for (const char* method : {"pmfg", "micro"})
    for (PixelFilterKind kind : {PixelFilterKind::Tent, PixelFilterKind::Mitchell}) {
      INFO(method << ", " << pixelFilterName(kind));
      const OptionValues values{{"spp", "2048"}, {"seed", "7"}, {"pixel_filter", pixelFilterName(kind)}};
      CHECK(largestZ(renderingMethod(method).render(scene, vis, values).image, kind, 2048) < 4.4);
    }
}
