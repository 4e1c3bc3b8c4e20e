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
#include "lucent/render/dump_compare.h"
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

// The candidate's arrays against the dump's, as lucent check-dump compares them.
const ArrayComparison& array(const DumpComparison& c, const std::string& name) {
  for (const ArrayComparison& a : c.arrays)
    if (a.name == name) return a;
  FAIL("no array " << name << " compared");
  return c.arrays.front();
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
  TempDir candidate("opencl-purcell-candidate");
  CHECK(writeKnnGridDumps(run, dir.path.string(), "global", "band0", candidate.path.string()) == 0);
  const DumpComparison c = compareDumpDirectories(dir.path.string(), candidate.path.string());
  INFO(dumpComparisonReport(c));
  CHECK(c.passed());
  CHECK(array(c, "band0.indirect").referenceRecords > 2000);
  CHECK(array(c, "band0.global.neighbours").rule == "neighbour sets");
  CHECK(c.arrays.size() == 2);

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
    std::set<uint32_t> kernel;
    for (uint32_t j = 0; j < run.found[i]; ++j) kernel.insert(run.neighbours[i * run.capacity + j].index);
    sameSets += kernel == lucent && kernel.size() == run.found[i] && run.radius2[i] == knnGridRadius2(s);
  }
  CHECK(overflow == 0);
  CHECK(sameSets == points.size());

  // A damaged photon list is refused before a kernel follows it.
  auto list = readDump<uint32_t>(dir / "global.photon_list.bin", "uint32");
  const uint32_t kept = list[7];
  list[7] = uint32_t(photons.size());
  writeDump(dir.path.string(), "global.photon_list", "uint32", std::span(list));
  CHECK_THROWS_WITH(runKnnGridEstimate(device(), dir.path.string(), "global", "band0", settings.k, settings.maxRadius),
                    Catch::Contains("global.photon_list.bin: entry 7"));
  list[7] = kept;
  writeDump(dir.path.string(), "global.photon_list", "uint32", std::span(list));

  // Without the dump's neighbours (a pmfg dump, whose indirect light is final gathering) the global
  // map's estimate has nothing to be compared with: refused.
  TempDir copy("opencl-purcell-copy");
  std::filesystem::copy(dir.path, copy.path, std::filesystem::copy_options::overwrite_existing);
  std::filesystem::remove(copy / "band0.global.neighbours.bin");
  CHECK_THROWS_WITH(writeKnnGridDumps(run, copy.path.string(), "global", "band0", candidate.path.string()),
                    Catch::Contains("band0.global.neighbours.bin is missing"));

  // The comparison can fail: one photon more per search changes the estimates where the search
  // found k (the others, with fewer than k within the maximum radius, keep every photon there).
  const KnnGridRun other = runKnnGridEstimate(device(), dir.path.string(), "global", "band0", settings.k + 1, settings.maxRadius);
  writeKnnGridDumps(other, dir.path.string(), "global", "band0", candidate.path.string());
  const DumpComparison d = compareDumpDirectories(dir.path.string(), candidate.path.string());
  CHECK(array(d, "band0.indirect").differing > 50);
  CHECK(array(d, "band0.global.neighbours").differing > 50);
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
  TempDir candidate("opencl-envpbgi-candidate");
  const size_t unreached = writeCacheDumps(run, dir.path.string(), candidate.path.string());
  const DumpComparison c = compareDumpDirectories(dir.path.string(), candidate.path.string());
  INFO(dumpComparisonReport(c));
  CHECK(c.passed());
  CHECK(array(c, "indirect").referenceRecords > 3000);
  // The receivers no cache reaches are those the render shaded from their own buffers.
  const auto fallbacks = std::find_if(out.stats.counters.begin(), out.stats.counters.end(),
                                      [](const auto& counter) { return counter.first == "cache_fallbacks"; });
  REQUIRE(fallbacks != out.stats.counters.end());
  CHECK(unreached == fallbacks->second);
  CHECK(unreached < 100);
  // The comparison can fail: a wider angle lets caches facing other ways lend their light.
  writeCacheDumps(runCacheInterpolation(device(), dir.path.string(), 60), dir.path.string(), candidate.path.string());
  CHECK(array(compareDumpDirectories(dir.path.string(), candidate.path.string()), "indirect").differing > 0);
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
    TempDir candidate("opencl-particles-candidate");
    writeParticleDumps(run, candidate.path.string());
    const DumpComparison c = compareDumpDirectories(dir.path.string(), candidate.path.string());
    INFO(dumpComparisonReport(c));
    CHECK(c.passed());
    CHECK(c.arrays.size() == 2);
    CHECK(array(c, "particles.radiance_particle_irradiance").referenceRecords > 500);

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
    writeParticleDumps(runParticleGathering(device(), dir.path.string()), candidate.path.string());
    const ArrayComparison broken =
        array(compareDumpDirectories(dir.path.string(), candidate.path.string()), "particles.gathered_irradiance");
    CHECK(broken.differing == 1);
    REQUIRE(broken.first.size() == 1);
    CHECK(broken.first[0].index == run.rowParticle[cut / perRow]);
  }
}
