// Environment lighting: a lat-long map loaded from a scene file, importance-sampled, must give the
// irradiance obtained by integrating the map numerically.
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>

#include "lucent/image/image.h"
#include "lucent/methods/pathtrace.h"
#include "lucent/scene/loader.h"
#include "test_support.h"

using namespace lucent;
namespace fs = std::filesystem;

namespace {

// A map with a smooth sky gradient and a small, very bright "sun" patch above the horizon.
Image makeSkyMap(int w, int h) {
  return test::rgbImage(w, h, [&](int x, int y) {
    const float v = (y + 0.5f) / h, u = (x + 0.5f) / w;
    if (y == h / 4 && x == w / 3) return Rgb(400.0f, 300.0f, 200.0f);
    return Rgb(0.2f + 0.8f * (1 - v), 0.3f + 0.5f * u, 0.5f);
  });
}

// Irradiance on a surface facing +y: sum over texels of L * max(0, cos) * solid angle, each texel
// subdivided to integrate the cosine accurately.
Rgb irradianceFacingUp(const Image& map) {
  const int w = map.width(), h = map.height(), sub = 16;
  double e[3] = {0, 0, 0};
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int sy = 0; sy < sub; ++sy)
        for (int sx = 0; sx < sub; ++sx) {
          const double theta = kPi * (y + (sy + 0.5) / sub) / h;
          const double dOmega = std::sin(theta) * (kPi / (h * sub)) * (2 * kPi / (w * sub));
          const double cosUp = std::cos(theta);  // v runs from +y down
          if (cosUp <= 0) continue;
          for (int k = 0; k < 3; ++k) e[k] += map.at(x, y, k) * cosUp * dOmega;
        }
  return Rgb(float(e[0]), float(e[1]), float(e[2]));
}

}  // namespace

TEST_CASE("Environment map: irradiance on a diffuse plane matches numerical integration", "[environment]") {
  const test::TempDir tmp("environment");
  const fs::path& dir = tmp.path;
  const Image map = makeSkyMap(64, 32);
  writeExr(map, (dir / "sky.exr").string());
  std::ofstream(dir / "plane.obj") << "mtllib plane.mtl\nusemtl white\n"
                                      "v -100 0 -100\nv -100 0 100\nv 100 0 100\nv 100 0 -100\nf 1 2 3 4\n";
  std::ofstream(dir / "plane.mtl") << "newmtl white\nKd 0.5 0.5 0.5\n";
  std::ofstream(dir / "scene.json") << R"({
    "camera": { "eye": [0, 5, 0], "look_at": [0, 0, 0.001], "up": [0, 0, 1], "fov_y": 40, "resolution": [24, 24] },
    "meshes": [ { "obj": "plane.obj" } ],
    "lights": [ { "type": "environment", "map": "sky.exr", "scale": 0.5 } ] })";
  const Scene scene = loadScene((dir / "scene.json").string(), {true});

  const Visibility vis(scene);
  PathTraceOptions opt;
  opt.common.spp = 256;
  opt.maxDepth = 1;
  opt.common.seed = 4;
  const RenderOutput out = renderPathTraced(scene, vis, opt);
  const Rgb expected = irradianceFacingUp(map) * (0.5f * 0.5f * kInvPi);  // scale * albedo / pi
  test::requireImageMean(out.image, expected);
}
