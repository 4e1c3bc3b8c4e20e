// Binary dumps (docs/dump-format.md): the file format itself, and that a photon-mapping render's dump
// holds enough to recompute a stage from the stages before it, as a GPU backend would be checked.
#include <catch2/catch.hpp>

#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>

#include "lucent/core/dump.h"
#include "lucent/methods/microrender.h"
#include "lucent/methods/photonmap.h"
#include "lucent/pipeline/shading_points.h"
#include "lucent/scene/loader.h"
#include "lucent/techniques/points/point_hierarchy.h"
#include "lucent/techniques/points/point_radiance.h"
#include "methods/photonmap/photon_maps.h"
#include "methods/photonmap/radiance_estimate.h"
#include "methods/photonmap/sorted_grid.h"
#include "methods/photonmap/stencil_grid.h"
#include "test_support.h"

using namespace lucent;
using lucent::test::TempDir;

TEST_CASE("Dumps hold their records behind a header that names them", "[dump]") {
  TempDir dir("dump");
  const std::vector<uint32_t> values = {7, 0, 0xffffffffu, 42};
  writeDump(dir.path.string(), "values", "uint32", std::span(values));
  const std::string path = dir / "values.bin";
  REQUIRE(std::filesystem::file_size(path) == sizeof(DumpHeader) + values.size() * 4);
  const DumpHeader header = readDumpHeader(path);
  CHECK(std::memcmp(header.magic, "LCNTDUMP", 8) == 0);
  CHECK(header.version == kDumpVersion);
  CHECK(header.recordBytes == 4);
  CHECK(header.count == values.size());
  CHECK(std::string(header.type) == "uint32");
  CHECK(readDump<uint32_t>(path, "uint32") == values);
  CHECK(dir.entries().size() == 1);  // no temporary file left behind

  // The wrong type, a file that is not a dump, another format version, bytes after the records, a
  // truncated one, and a directory that is not there.
  CHECK_THROWS_WITH(readDump<float>(path, "float"), Catch::Contains("values.bin") && Catch::Contains("uint32"));
  {
    std::ofstream(dir / "not-a-dump.bin") << "hello, this is text and not a dump file at all, sixty-four bytes";
  }
  CHECK_THROWS_WITH(readDumpHeader(dir / "not-a-dump.bin"), Catch::Contains("not a Lucent dump"));
  auto rewriteHeader = [&](const DumpHeader& h) {
    std::fstream file(path, std::ios::binary | std::ios::in | std::ios::out);
    file.write(reinterpret_cast<const char*>(&h), sizeof h);
  };
  DumpHeader otherVersion = header;
  otherVersion.version = kDumpVersion + 1;
  rewriteHeader(otherVersion);
  CHECK_THROWS_WITH(readDumpHeader(path), Catch::Contains("values.bin") && Catch::Contains("format version 2"));
  CHECK_THROWS_WITH(readDump<uint32_t>(path, "uint32"), Catch::Contains("format version 2"));
  DumpHeader fewer = header;
  fewer.count = values.size() - 1;
  rewriteHeader(fewer);
  CHECK_THROWS_WITH(readDump<uint32_t>(path, "uint32"), Catch::Contains("values.bin") && Catch::Contains("4 bytes after its 3 records"));
  rewriteHeader(header);
  REQUIRE(readDump<uint32_t>(path, "uint32") == values);
  std::filesystem::resize_file(path, sizeof(DumpHeader) + 6);
  CHECK_THROWS_WITH(readDump<uint32_t>(path, "uint32"), Catch::Contains("truncated"));
  // A damaged count is refused against the file's length, before anything is allocated.
  DumpHeader damaged = header;
  damaged.count = uint64_t(1) << 60;
  rewriteHeader(damaged);
  CHECK_THROWS_WITH(readDump<uint32_t>(path, "uint32"), Catch::Contains("truncated"));
  // A missing directory is created; a file where the directory would be is named.
  CHECK_NOTHROW(writeDump((dir.path / "missing").string(), "values", "uint32", std::span(values)));
  CHECK(readDump<uint32_t>((dir.path / "missing" / "values.bin").string(), "uint32") == values);
  std::ofstream(dir.path / "blocked") << "x";
  CHECK_THROWS_WITH(writeDump((dir.path / "blocked").string(), "values", "uint32", std::span(values)),
                    Catch::Contains("blocked"));
}

TEST_CASE("A purcell dump recomputes its maps and its caustic estimates", "[dump][photonmap-render]") {
  // What a GPU port would do stage by stage: take the photons Lucent traced, build the sorted grid
  // from them, and estimate at Lucent's shading points; each stage must match Lucent's dump exactly.
  TempDir dir("purcell-dump");
  Scene scene = loadScene(LUCENT_SOURCE_DIR "/scenes/glass-ball.json", {true});
  scene.camera.width = 48, scene.camera.height = 36;
  const Visibility vis(scene);
  PhotonMapOptions opt;
  opt.photons = 2000;
  opt.causticPhotons = 4000;
  opt.k = 16;
  opt.shading.lightSamples = 2;
  opt.map = PhotonMapKind::Sort;
  opt.photonsPerCell = 2;
  opt.shading.dumpDirectory = dir.path.string();
  const RenderOutput out = renderPurcell(scene, vis, opt);

  const auto photons = readDump<Photon>(dir / "caustic.photons.bin", "Photon");
  const auto grid = readDump<UniformGrid>(dir / "caustic.grid.bin", "UniformGrid");
  const auto points = readDump<ShadingPoint>(dir / "band0.shading_points.bin", "ShadingPoint");
  const auto caustic = readDump<Rgb>(dir / "band0.caustic.bin", "Rgb");
  REQUIRE(grid.size() == 1);
  REQUIRE(photons.size() > 1000);
  REQUIRE(points.size() > 500);
  REQUIRE(caustic.size() == points.size());
  CHECK(readDump<Rgb>(dir / "band0.direct.bin", "Rgb").size() == points.size());
  for (const char* name : {"global.photons.bin", "global.photon_list.bin", "global.first_photon.bin",
                           "global.cell_counts.bin", "caustic.cell_counts.bin"})
    CHECK(std::filesystem::exists(dir / name));

  // The map, from the dumped photons with the render's grid options.
  const EstimateSettings settings = estimateSettingsFor(scene, opt).caustic;
  const SortedGrid map = buildSortedGrid(photons, gridOptionsFor(opt, settings.k));
  CHECK(std::memcmp(&map.grid, &grid[0], sizeof(UniformGrid)) == 0);
  CHECK(map.photonList == readDump<uint32_t>(dir / "caustic.photon_list.bin", "uint32"));
  CHECK(map.firstPhoton == readDump<uint32_t>(dir / "caustic.first_photon.bin", "uint32"));
  CHECK(map.cellCounts.prefix == readDump<uint32_t>(dir / "caustic.cell_counts.bin", "uint32"));

  // The estimates, at the dumped shading points, one search each: the render takes them cell by
  // cell (estimate_by_cell.h), the same photons and radius summed in another order, so they agree
  // to the sums' rounding (a few float ulps of sums of about a hundred positive terms).
  EstimateCounters counters;
  size_t lit = 0, equal = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    const Rgb e = estimateRadiance(map, estimatePoint(points[i]), settings, nullptr, counters);
    bool same = true;
    for (int ch = 0; ch < 3; ++ch) same &= std::abs(e[ch] - caustic[i][ch]) <= 1e-5f * std::max(e[ch], caustic[i][ch]);
    equal += same;
    lit += e.maxComponent() > 0;
  }
  CHECK(equal == points.size());
  CHECK(lit > 50);  // the caustic under the ball is in view
  CHECK(out.stats.stageSeconds.size() > 0);
}

TEST_CASE("Stencil and hashed grid dumps hold the routing and the buckets their photons give", "[dump][photonmap-render]") {
  // The stencil grid's dump: each cell's slots hold the first m^2 photons, in index order, of
  // those whose positions fall in it, `arrived` counts them all, and the cell counts are of the
  // stored ones. The hashed grid's dump: a rebuild from its photons (as traced) with the render's
  // options gives the same list, keys and buckets.
  Scene scene = loadScene(LUCENT_SOURCE_DIR "/scenes/cornell-box-spheres.json", {true});
  scene.camera.width = 24, scene.camera.height = 18;
  const Visibility vis(scene);
  PhotonMapOptions opt;
  opt.photons = 3000;
  opt.causticPhotons = 6000;
  opt.k = 16;
  opt.shading.lightSamples = 1;
  opt.photonsPerCell = 2;
  opt.stencilSide = 3;  // few slots: crowded cells overflow
  for (PhotonMapKind kind : {PhotonMapKind::Stencil, PhotonMapKind::Hash}) {
    TempDir dir("grid-dump");
    opt.map = kind;
    opt.shading.dumpDirectory = dir.path.string();
    renderPurcell(scene, vis, opt);
    for (const std::string map : {"global", "caustic"}) {
      INFO(map << (kind == PhotonMapKind::Stencil ? " stencil" : " hash"));
      const auto photons = readDump<Photon>(dir / (map + ".photons.bin"), "Photon");
      const auto grids = readDump<UniformGrid>(dir / (map + ".grid.bin"), "UniformGrid");
      REQUIRE(grids.size() == 1);
      REQUIRE(photons.size() > 500);
      const UniformGrid& grid = grids[0];
      if (kind == PhotonMapKind::Stencil) {
        const auto slots = readDump<uint32_t>(dir / (map + ".slots.bin"), "uint32");
        const auto arrived = readDump<uint32_t>(dir / (map + ".arrived.bin"), "uint32");
        const uint32_t m2 = opt.stencilSide * opt.stencilSide;
        REQUIRE(arrived.size() == grid.cellCount());
        REQUIRE(slots.size() == arrived.size() * m2);
        std::vector<uint32_t> expectedSlots(slots.size(), StencilGrid::kEmptySlot), expectedArrived(arrived.size(), 0),
            stored(arrived.size(), 0);
        for (uint32_t i = 0; i < photons.size(); ++i) {
          const uint32_t c = grid.cellIndex(grid.cellOf(photons[i].position));
          if (expectedArrived[c]++ < m2) expectedSlots[size_t(c) * m2 + stored[c]++] = i;
        }
        CHECK(arrived == expectedArrived);
        CHECK(slots == expectedSlots);
        CHECK(readDump<uint32_t>(dir / (map + ".cell_counts.bin"), "uint32") ==
              buildCellCountTable(grid, [&](uint32_t c) { return stored[c]; }).prefix);
        size_t overflowing = 0;
        for (uint32_t n : arrived) overflowing += n > m2;
        CHECK(overflowing > 0);
      } else {
        const MapEstimateSettings settings = estimateSettingsFor(scene, opt);
        const uint32_t k = map == "global" ? settings.global.k : settings.caustic.k;
        const HashedGrid map2 = buildHashedGrid(photons, gridOptionsFor(opt, k));
        CHECK(std::memcmp(&map2.grid, &grid, sizeof(UniformGrid)) == 0);
        CHECK(map2.photonList == readDump<uint32_t>(dir / (map + ".photon_list.bin"), "uint32"));
        CHECK(map2.cellKeys == readDump<uint64_t>(dir / (map + ".cell_keys.bin"), "uint64"));
        CHECK(map2.firstPhoton == readDump<uint32_t>(dir / (map + ".first_photon.bin"), "uint32"));
      }
    }
  }
}

TEST_CASE("A micro dump's interior radiance pulls up from its leaves", "[dump][micro]") {
  // Section 4's pull, recomputed from the dumped leaves' radiance and the nodes' areas, must give
  // the dumped interior radiance; the paper's half floats must be those values rounded.
  TempDir dir("micro-dump");
  Scene scene = loadScene(LUCENT_SOURCE_DIR "/scenes/cornell-box.json", {true});
  scene.camera.width = scene.camera.height = 16;
  const Visibility vis(scene);
  MicroRenderOptions opt;
  opt.points = 1024;
  opt.encoding = NodeEncoding::Packed;
  opt.shading.dumpDirectory = dir.path.string();
  renderMicro(scene, vis, opt);

  PointHierarchy h;
  h.leafCount = 1024;
  h.nodeAreas = readDump<float>(dir / "hierarchy.node_areas.bin", "float");
  const auto radiance = readDump<Rgb>(dir / "point_radiance.bin", "Rgb");
  REQUIRE(h.nodeAreas.size() == 2048);
  REQUIRE(radiance.size() == 2048);
  CHECK(readDump<PointSample>(dir / "hierarchy.points.bin", "PointSample").size() == 1024);
  CHECK(readDump<FloatNode>(dir / "hierarchy.float_nodes.bin", "FloatNode").size() == 2048);
  CHECK(readDump<PackedNode>(dir / "hierarchy.packed_nodes.bin", "PackedNode").size() == 2048);
  CHECK(readDump<NodeQuantization>(dir / "hierarchy.quantization.bin", "NodeQuantization").size() == 1);
  std::vector<Rgb> pulled(radiance.begin(), radiance.end());
  for (uint32_t i = 1; i < h.leafCount; ++i) pulled[i] = Rgb(-1.0f);  // interior nodes recomputed
  pullRadiance(h, pulled);
  size_t equal = 0, lit = 0;
  for (uint32_t i = 1; i < 2048; ++i) equal += pulled[i] == radiance[i], lit += radiance[i].maxComponent() > 0;
  CHECK(equal == 2047);
  CHECK(lit > 500);
  const auto half = readDump<HalfRgb>(dir / "point_radiance_half.bin", "HalfRgb");
  REQUIRE(half.size() == 2048);
  size_t rounded = 0;
  for (uint32_t i = 1; i < 2048; ++i) {
    const HalfRgb expected = toHalf(radiance[i]);
    rounded += half[i].r == expected.r && half[i].g == expected.g && half[i].b == expected.b;
  }
  CHECK(rounded == 2047);
  // The interior nodes' directional radiance, recomputed from the dumped leaves.
  h.floatNodes = readDump<FloatNode>(dir / "hierarchy.float_nodes.bin", "FloatNode");
  const auto directional = readDump<DirectionalRadiance>(dir / "point_radiance_directional.bin", "DirectionalRadiance");
  REQUIRE(directional.size() == 1024);
  const std::vector<DirectionalRadiance> expected = directionalRadiance(h, radiance);
  size_t same = 0;
  for (uint32_t i = 1; i < 1024; ++i) same += std::memcmp(&expected[i], &directional[i], sizeof(DirectionalRadiance)) == 0;
  CHECK(same == 1023);
  const auto points = readDump<ShadingPoint>(dir / "shading_points.bin", "ShadingPoint");
  CHECK(points.size() > 100);
  CHECK(readDump<Rgb>(dir / "indirect.bin", "Rgb").size() == points.size());
}

TEST_CASE("The CLI dumps pmfg's and micro's stages into a directory it creates, and refuses --dump for pt",
          "[dump][cli]") {
  TempDir dir("cli-dump");
  const std::string scene = lucent::test::quoted(LUCENT_SOURCE_DIR "/scenes/cornell-box.json");
  const std::string common = " --resolution 16x16 --photons 500 --caustic-photons 0 --quiet -o " +
                             lucent::test::quoted(dir / "out.exr");
  const auto run = lucent::test::runLucent("render " + scene + " --method pmfg --gather-rays 4 --dump " +
                                           lucent::test::quoted(dir.path.string()) + common);
  INFO(run.output);
  REQUIRE(run.status == 0);
  CHECK(std::filesystem::exists(dir / "global.photons.bin"));
  CHECK(std::filesystem::exists(dir / "global.source_index.bin"));  // pmfg's kd-tree
  CHECK(std::filesystem::exists(dir / "band0.indirect.bin"));
  // Beside the arrays, what made them: every option and the values derived from them.
  {
    std::ifstream in(dir / "settings.json");
    const auto settings = nlohmann::json::parse(in);
    CHECK(settings["method"] == "pmfg");
    CHECK(settings["options"]["gather_rays"] == 4);
    CHECK(settings["options"]["photons"] == 500);
    CHECK(settings["options"].contains("k"));
    CHECK(settings["derived"]["max_radius"].get<double>() > 0);
    CHECK(settings["derived"].contains("caustic_k"));
    CHECK(settings["width"] == 16);
    CHECK(settings["height"] == 16);
    CHECK(settings["camera"]["fov_y"].get<double>() > 0);
  }

  // A missing directory is created, with its missing parents; a file in the way is refused.
  const auto missing = lucent::test::runLucent("render " + scene + " --method purcell --dump " +
                                               lucent::test::quoted(dir / "new/dumps") + common);
  INFO(missing.output);
  CHECK(missing.status == 0);
  CHECK(std::filesystem::exists(dir / "new/dumps/global.photons.bin"));
  std::ofstream(dir / "file") << "x";
  const auto blocked = lucent::test::runLucent("render " + scene + " --method purcell --dump " +
                                               lucent::test::quoted(dir / "file/dumps") + common);
  CHECK(blocked.status != 0);
  CHECK_THAT(blocked.output, Catch::Contains("is not a directory"));
  // micro: the hierarchy, the points' radiance, the shading points and, lit by photons, the map.
  TempDir microDir("cli-micro-dump");
  const auto micro = lucent::test::runLucent(
      "render " + scene + " --method micro --lighting photons --photons 2000 --points 1024 --dump " +
      lucent::test::quoted(microDir.path.string()) + " --resolution 16x16 --quiet -o " +
      lucent::test::quoted(microDir / "micro.exr"));
  INFO(micro.output);
  REQUIRE(micro.status == 0);
  CHECK(readDump<PointSample>(microDir / "hierarchy.points.bin", "PointSample").size() == 1024);
  CHECK(readDump<Rgb>(microDir / "point_radiance.bin", "Rgb").size() == 2048);
  const auto microPoints = readDump<ShadingPoint>(microDir / "shading_points.bin", "ShadingPoint");
  CHECK(readDump<Rgb>(microDir / "indirect.bin", "Rgb").size() == microPoints.size());
  const auto photons = readDump<Photon>(microDir / "global.photons.bin", "Photon");
  CHECK(photons.size() > 1000);
  CHECK(readDump<uint32_t>(microDir / "global.source_index.bin", "uint32").size() == photons.size());

  const auto pt = lucent::test::runLucent("render " + scene + " --method pt --dump " +
                                          lucent::test::quoted(dir.path.string()) + " --resolution 16x16 --quiet -o " +
                                          lucent::test::quoted(dir / "pt.exr"));
  CHECK(pt.status != 0);
  CHECK_FALSE(std::filesystem::exists(dir / "pt.exr"));
}
