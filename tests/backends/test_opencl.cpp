// The OpenCL kernels of backends/opencl read Lucent's dumps and recompute stages on an OpenCL
// device (PoCL on the CPU here; a missing device or a failed kernel build fails, never skips): the
// records' layout on both sides, Purcell's kNN-grid estimate and the particle-space gathering.
#include <catch2/catch.hpp>

#include <algorithm>
#include <filesystem>
#include <set>
#include <string>

#include "dump_kernels.h"
#include "lucent/core/dump.h"
#include "lucent/methods/envpbgi.h"
#include "lucent/methods/particles.h"
#include "lucent/methods/photonmap.h"
#include "lucent/pipeline/shading_points.h"
#include "lucent/scene/loader.h"
#include "methods/particles/area_particles.h"
#include "methods/photonmap/knn_grid.h"
#include "methods/photonmap/photon_maps.h"
#include "methods/photonmap/sorted_grid.h"
#include "test_support.h"

using namespace lucent;
using namespace lucent::opencl;
using lucent::test::TempDir;

namespace {

const Device& device() {
  static const Device d;  // throws, failing the test, where there is no OpenCL device
  return d;
}

bool differenceNamed(const std::vector<std::string>& lines, const std::string& text) {
  return std::any_of(lines.begin(), lines.end(), [&](const std::string& l) { return l.find(text) != std::string::npos; });
}

}  // namespace

TEST_CASE("The OpenCL C records lay out every field as the C++ structs do, and a shifted field is caught", "[opencl]") {
  const std::string records(kernelSource("records.cl"));
  REQUIRE_FALSE(records.empty());
  const std::vector<FieldLayout> cpp = cppRecordLayout();
  REQUIRE(cpp.size() > 40);
  CHECK(layoutDifferences(cpp, openclRecordLayout(device(), records)).empty());

  // A field moved by four bytes: the photon's flags behind an extra word.
  std::string shifted = records;
  const size_t flags = shifted.find("  uint flags;");
  REQUIRE(flags != std::string::npos);
  shifted.insert(flags, "  uint extra;\n");
  const std::vector<std::string> d = layoutDifferences(cpp, openclRecordLayout(device(), shifted));
  CHECK(differenceNamed(d, "Photon.flags: offset 28 in C++, 32 in OpenCL C"));
  CHECK(differenceNamed(d, "Photon: 32 bytes in C++, 36 in OpenCL C"));
  // The 3-component vector type a port might reach for: 16 bytes in OpenCL C, not 12.
  std::string float3 = records;
  const size_t vec3 = float3.find("typedef struct {\n  float x, y, z;\n} Vec3;");
  REQUIRE(vec3 != std::string::npos);
  float3.replace(vec3, std::string("typedef struct {\n  float x, y, z;\n} Vec3;").size(),
                 "typedef union { float3 v; struct { float x, y, z; }; } Vec3;");
  CHECK(differenceNamed(layoutDifferences(cpp, openclRecordLayout(device(), float3)), "Vec3: 12 bytes in C++, 16 in OpenCL C"));
}

TEST_CASE("The OpenCL kNN-grid estimate equals a purcell dump's, with the same neighbours as Lucent's search",
          "[opencl][dump]") {
  TempDir dir("opencl-purcell");
  Scene scene = loadScene(LUCENT_SOURCE_DIR "/scenes/cornell-box.json", {true});
  scene.camera.width = 48, scene.camera.height = 48;
  const Visibility vis(scene);
  PhotonMapOptions opt;
  opt.photons = 20000;
  opt.k = 30;
  opt.shading.lightSamples = 1;
  opt.map = PhotonMapKind::Sort;
  opt.shading.dumpDirectory = dir.path.string();
  renderPurcell(scene, vis, opt);
  const EstimateSettings settings = estimateSettingsFor(scene, opt).global;

  const KnnGridRun run = runKnnGridEstimate(device(), dir.path.string(), "global", "band0", settings.k, settings.maxRadius);
  const StageCheck check = checkKnnGridEstimate(run, dir.path.string(), "global", "band0", 1e-5);
  INFO(check.note << "; worst relative difference " << check.worstRelative);
  CHECK(check.compared > 2000);
  CHECK(check.differing == 0);
  CHECK(check.passed());

  // The neighbour sets against Lucent's own search on the map rebuilt from the dumped photons. Ties
  // at the radius cannot change a set (every photon within it is accepted), only which photon the
  // estimate leaves out.
  const auto photons = readDump<Photon>(dir / "global.photons.bin", "Photon");
  const auto points = readDump<ShadingPoint>(dir / "band0.shading_points.bin", "ShadingPoint");
  const SortedGrid map = buildSortedGrid(photons, gridOptionsFor(opt, settings.k));
  size_t sameSets = 0, overflow = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    std::set<uint32_t> lucent;
    const KnnGridSearch s = knnGrid(map, points[i].position, settings.k, settings.maxRadius,
                                    [&](uint32_t id, const Photon&, float) { lucent.insert(id); });
    if (run.found[i] > run.capacity) {
      ++overflow;
      continue;
    }
    const uint32_t* ids = run.neighbours.data() + i * run.capacity;
    const std::set<uint32_t> kernel(ids, ids + run.found[i]);
    sameSets += kernel == lucent && kernel.size() == run.found[i] && run.radius2[i] == knnGridRadius2(s);
  }
  CHECK(overflow == 0);
  CHECK(sameSets == points.size());

  // The comparison can fail: one photon more per search changes the estimates where the search
  // found k (the others, with fewer than k within the maximum radius, keep every photon there).
  const KnnGridRun other = runKnnGridEstimate(device(), dir.path.string(), "global", "band0", settings.k + 1, settings.maxRadius);
  CHECK(checkKnnGridEstimate(other, dir.path.string(), "global", "band0", 1e-5).differing > 50);
}

TEST_CASE("The OpenCL radiance-cache interpolation equals an envpbgi dump's indirect light", "[opencl][dump]") {
  TempDir dir("opencl-envpbgi");
  Scene scene = loadScene(LUCENT_SOURCE_DIR "/scenes/primitives.json", {true});
  scene.camera.width = 96, scene.camera.height = 54;
  const Visibility vis(scene);
  EnvPbgiOptions o;
  o.points = 1u << 14;
  o.dumpDirectory = dir.path.string();
  const RenderOutput out = renderEnvPbgi(scene, vis, o);

  const CacheInterpolationRun run = runCacheInterpolation(device(), dir.path.string(), o.cacheMaxAngle);
  const StageCheck check = checkCacheInterpolation(run, dir.path.string(), 1e-5);
  INFO(check.note << "; worst relative difference " << check.worstRelative);
  CHECK(check.compared > 3000);
  CHECK(check.passed());
  // The receivers no cache reaches are those the render shaded from their own buffers.
  const auto fallbacks = std::find_if(out.stats.counters.begin(), out.stats.counters.end(),
                                      [](const auto& c) { return c.first == "cache_fallbacks"; });
  REQUIRE(fallbacks != out.stats.counters.end());
  CHECK(size_t(std::count(run.reached.begin(), run.reached.end(), 0u)) == fallbacks->second);
  // The comparison can fail: a wider angle lets caches facing other ways lend their light.
  const CacheInterpolationRun wider = runCacheInterpolation(device(), dir.path.string(), 60);
  CHECK(checkCacheInterpolation(wider, dir.path.string(), 1e-5).differing > 0);
}

TEST_CASE("The OpenCL particle gathering equals a particles dump's gathered and estimated irradiance", "[opencl][dump]") {
  TempDir dir("opencl-particles");
  Scene scene = loadScene(LUCENT_SOURCE_DIR "/scenes/cornell-box.json", {true});
  scene.camera.width = 48, scene.camera.height = 48;
  const Visibility vis(scene);
  for (ParticleGeometry geometry : {ParticleGeometry::Frame, ParticleGeometry::All}) {
    ParticleOptions o;
    o.areaParticles = 4000;
    o.bounces = 2;
    o.shading.lightSamples = 1;
    o.geometry = geometry;
    o.shading.dumpDirectory = dir.path.string();
    for (const auto& entry : std::filesystem::directory_iterator(dir.path)) std::filesystem::remove(entry.path());
    renderParticles(scene, vis, o);
    INFO("geometry " << (geometry == ParticleGeometry::All ? "all" : "frame"));

    const ParticleGatheringRun run = runParticleGathering(device(), dir.path.string());
    const std::vector<StageCheck> checks = checkParticleGathering(run, dir.path.string(), 1e-6);
    REQUIRE(checks.size() == 2);
    for (const StageCheck& c : checks) {
      INFO(c.stage << ": " << c.differing << " of " << c.compared << " differ, worst " << c.worstRelative);
      CHECK(c.compared > 500);
      CHECK(c.passed());
    }

    // One link of one used particle that reaches a lit particle cut: that particle's gathered
    // irradiance is no longer the dump's.
    auto links = readDump<uint32_t>(dir / "particles.gather_links.bin", "uint32");
    const auto used = readDump<uint32_t>(dir / "particles.used_area_particles.bin", "uint32");
    const auto radiance = readDump<Rgb>(dir / "particles.radiance.bin", "Rgb");
    const std::set<uint32_t> usedSet(used.begin(), used.end());
    const size_t perRow = links.size() / run.rowParticle.size();
    size_t cut = links.size();
    for (size_t j = 0; j < links.size() && cut == links.size(); ++j)
      if (usedSet.count(run.rowParticle[j / perRow]) && links[j] != kNoParticle && radiance[links[j]].maxComponent() > 0)
        cut = j;
    REQUIRE(cut < links.size());
    links[cut] = kNoParticle;
    writeDump(dir.path.string(), "particles.gather_links", "uint32", std::span(links));
    const std::vector<StageCheck> broken = checkParticleGathering(runParticleGathering(device(), dir.path.string()),
                                                                  dir.path.string(), 1e-6);
    CHECK(broken[0].differing == 1);
    CHECK(broken[0].firstDiffering == run.rowParticle[cut / perRow]);
  }
}
