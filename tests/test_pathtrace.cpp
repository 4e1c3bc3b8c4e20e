// The reference path tracer against analytic answers (furnaces) and for determinism.
#include <catch2/catch.hpp>

#include <cmath>

#include "lucent/core/parallel.h"
#include "lucent/methods/pathtrace.h"
#include "lucent/scene/loader.h"
#include "test_scenes.h"
#include "test_support.h"

using namespace lucent;

TEST_CASE("Closed diffuse furnace: radiance converges to Le / (1 - rho)", "[pathtrace][furnace]") {
  const Rgb rho(0.5f, 0.7f, 0.3f), le(1.0f, 2.0f, 0.5f);
  Scene scene;
  Material m;
  m.kd = rho;
  m.ke = le;
  test::addBox(scene, {-1, -1, -1}, {1, 1, 1}, test::addMaterial(scene, m, "walls"), true);
  scene.camera = test::testCamera({0.1f, 0.2f, 0.3f}, {0.5f, 0.1f, -1}, 32, 32, 90);
  finalizeScene(scene);
  const Visibility vis(scene);
  PathTraceOptions opt;
  opt.spp = 64;
  opt.maxDepth = 100000;
  opt.seed = 7;
  const RenderOutput out = renderPathTraced(scene, vis, opt);
  test::requireImageMean(out.image, Rgb(le.r / (1 - rho.r), le.g / (1 - rho.g), le.b / (1 - rho.b)));
}

TEST_CASE("Closed diffuse furnace with max depth: geometric series truncated", "[pathtrace][furnace]") {
  // With emission seen directly plus `d` bounces of lighting, L = Le (1 + rho + ... + rho^d).
  const float rho = 0.6f;
  Scene scene;
  Material m;
  m.kd = Rgb(rho);
  m.ke = Rgb(1.0f);
  test::addBox(scene, {-1, -1, -1}, {1, 1, 1}, test::addMaterial(scene, m, "walls"), true);
  scene.camera = test::testCamera({0, 0, 0}, {0, 0, -1}, 32, 32, 90);
  finalizeScene(scene);
  const Visibility vis(scene);
  for (int depth : {1, 2, 4}) {
    PathTraceOptions opt;
    opt.spp = 32;
    opt.maxDepth = depth;
    opt.seed = 3;
    const RenderOutput out = renderPathTraced(scene, vis, opt);
    float expected = 0, term = 1;
    for (int d = 0; d <= depth; ++d, term *= rho) expected += term;
    INFO("max depth " << depth);
    test::requireImageMean(out.image, Rgb(expected));
  }
}

TEST_CASE("White furnace: a convex white object under a constant environment vanishes", "[pathtrace][furnace]") {
  Scene scene;
  Material white;
  white.kd = Rgb(1.0f);
  test::addBox(scene, {-1, -1, -1}, {1, 1, 1}, test::addMaterial(scene, white, "white"), false);
  scene.camera = test::testCamera({2.5f, 1.5f, 3.5f}, {0, 0, 0}, 32, 32, 50);
  scene.environment.present = true;
  scene.environment.radiance = Rgb(0.8f, 1.0f, 1.2f);
  finalizeScene(scene);
  const Visibility vis(scene);
  PathTraceOptions opt;
  opt.spp = 64;
  opt.seed = 11;
  const RenderOutput out = renderPathTraced(scene, vis, opt);
  test::requireImageMean(out.image, scene.environment.radiance);
}

TEST_CASE("Renders are bit-identical whatever the thread count and tile size", "[pathtrace][determinism]") {
  const Scene scene = loadScene(LUCENT_SOURCE_DIR "/scenes/cornell-box.json", {true});
  Scene small = scene;
  small.camera.width = 48;
  small.camera.height = 40;
  PathTraceOptions opt;
  opt.spp = 8;
  opt.layers = true;
  opt.seed = 5;
  std::vector<float> reference;
  for (const auto& [threads, tile] : {std::pair{1, 16}, std::pair{2, 16}, std::pair{2, 7}, std::pair{1, 5}}) {
    ParallelScope scope(threads);
    const Visibility vis(small);
    opt.tileSize = tile;
    const RenderOutput out = renderPathTraced(small, vis, opt);
    if (reference.empty()) {
      reference = out.image.pixels();
    } else {
      INFO(threads << " threads, tile size " << tile);
      REQUIRE(out.image.pixels() == reference);
    }
  }
}
