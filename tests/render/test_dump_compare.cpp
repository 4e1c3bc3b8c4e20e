// lucent check-dump's rules (lucent/render/dump_compare.h): each array kind finds a one-record
// difference, naming the record and field, and lets through what its rule allows (photons
// reordered, a float within the tolerance, ties at a search's radius, a tree numbered otherwise).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cstddef>
#include <map>
#include <cmath>
#include <random>

#include "lucent/core/dump.h"
#include "lucent/render/dump_records.h"
#include "lucent/pipeline/shading_points.h"
#include "lucent/techniques/points/point_hierarchy.h"
#include "lucent/techniques/points/point_nodes.h"
#include "lucent/techniques/points/point_radiance.h"
#include "methods/envpbgi/radiance_cache.h"
#include "methods/particles/area_particles.h"
#include "methods/particles/radiance_particles.h"
#include "lucent/render/dump_compare.h"
#include "lucent/techniques/photons/kd_tree.h"
#include "lucent/techniques/photons/photon.h"
#include "methods/envpbgi/env_points.h"
#include "methods/photonmap/uniform_grid.h"
#include "test_support.h"

using namespace lucent;
using lucent::test::TempDir;

namespace {

struct Dirs {
  TempDir reference{"check-dump-reference"}, candidate{"check-dump-candidate"};
  template <class T>
  void write(const std::string& name, const std::string& type, const std::vector<T>& r, const std::vector<T>& c) {
    writeDump(reference.path.string(), name, type, std::span(r));
    writeDump(candidate.path.string(), name, type, std::span(c));
  }
  ArrayComparison compare(const std::string& name) const {
    const DumpComparison all = compareDumpDirectories(reference.path.string(), candidate.path.string());
    for (const ArrayComparison& a : all.arrays)
      if (a.name == name) return a;
    FAIL("no comparison of " << name);
    return {};
  }
};

float nextFloat(float x) { return std::nextafter(x, INFINITY); }

}  // namespace

TEST_CASE("The dump record table gives every field at the C++ struct's offset and every record its size", "[dump]") {
  // Per type, the C++ offset of each field of the table, in the table's order, and the struct's size.
#define AT(T, f) uint32_t(offsetof(T, f))
  const std::map<std::string, std::pair<std::vector<uint32_t>, size_t>> cpp = {
      {"uint32", {{0}, 4}},
      {"uint64", {{0}, 8}},
      {"float", {{0}, 4}},
      {"Rgb", {{AT(Rgb, r)}, sizeof(Rgb)}},
      {"HalfRgb", {{AT(HalfRgb, r)}, sizeof(HalfRgb)}},
      {"Photon", {{AT(Photon, position), AT(Photon, power), AT(Photon, direction), AT(Photon, flags)}, sizeof(Photon)}},
      {"PhotonDistance", {{AT(PhotonDistance, d2), AT(PhotonDistance, index)}, sizeof(PhotonDistance)}},
      {"UniformGrid", {{AT(UniformGrid, lo), AT(UniformGrid, hi), AT(UniformGrid, cellSize), AT(UniformGrid, invCellSize),
                        AT(UniformGrid, res), AT(UniformGrid, slack)}, sizeof(UniformGrid)}},
      {"DirectionalRadiance", {{AT(DirectionalRadiance, shown), AT(DirectionalRadiance, area)}, sizeof(DirectionalRadiance)}},
      {"PointSample", {{AT(PointSample, triangle), AT(PointSample, b1), AT(PointSample, b2)}, sizeof(PointSample)}},
      {"FloatNode", {{AT(FloatNode, sphere.center), AT(FloatNode, sphere.radius), AT(FloatNode, cone.axis),
                      AT(FloatNode, cone.angle), AT(FloatNode, albedo)}, sizeof(FloatNode)}},
      {"PackedNode", {{AT(PackedNode, position), AT(PackedNode, radius), AT(PackedNode, normalAlbedo), AT(PackedNode, coneFree)},
                      sizeof(PackedNode)}},
      {"NodeQuantization", {{AT(NodeQuantization, origin), AT(NodeQuantization, step), AT(NodeQuantization, radiusStep)},
                            sizeof(NodeQuantization)}},
      {"EnvPointNode", {{AT(EnvPointNode, position), AT(EnvPointNode, radius), AT(EnvPointNode, normal), AT(EnvPointNode, coneAngle),
                         AT(EnvPointNode, child), AT(EnvPointNode, skip), AT(EnvPointNode, selection)}, sizeof(EnvPointNode)}},
      {"Surfel", {{AT(Surfel, position), AT(Surfel, normal)}, sizeof(Surfel)}},
      {"RadianceCache", {{AT(RadianceCache, position), AT(RadianceCache, normal), AT(RadianceCache, radius),
                          AT(RadianceCache, environment), AT(RadianceCache, indirect)}, sizeof(RadianceCache)}},
      {"AreaParticle", {{AT(AreaParticle, position), AT(AreaParticle, normal), AT(AreaParticle, area), AT(AreaParticle, reflectance),
                         AT(AreaParticle, triangle)}, sizeof(AreaParticle)}},
      {"TriangleTessellation", {{AT(TriangleTessellation, first), AT(TriangleTessellation, segments)}, sizeof(TriangleTessellation)}},
      {"ShadingPoint", {{AT(ShadingPoint, position), AT(ShadingPoint, geometricNormal), AT(ShadingPoint, normal), AT(ShadingPoint, wo),
                         AT(ShadingPoint, weight), AT(ShadingPoint, bsdf.type), AT(ShadingPoint, bsdf.lambertian.kd),
                         AT(ShadingPoint, bsdf.phong.kd), AT(ShadingPoint, bsdf.phong.ks), AT(ShadingPoint, bsdf.phong.ns),
                         AT(ShadingPoint, bsdf.gltf.kd), AT(ShadingPoint, bsdf.gltf.ks), AT(ShadingPoint, bsdf.gltf.alpha),
                         AT(ShadingPoint, bsdf.gltf.f90), AT(ShadingPoint, bsdf.gltf.dielectricF0),
                         AT(ShadingPoint, bsdf.gltf.dielectricF90), AT(ShadingPoint, bsdf.gltf.masking),
                         AT(ShadingPoint, bsdf.gltf.sheenColour), AT(ShadingPoint, bsdf.gltf.sheenRoughness),
                         AT(ShadingPoint, bsdf.gltf.coat), AT(ShadingPoint, bsdf.gltf.coatAlpha),
                         AT(ShadingPoint, bsdf.gltf.coatNormal), AT(ShadingPoint, bsdf.gltf.transmission),
                         AT(ShadingPoint, bsdf.gltf.volumeIor),
                         AT(ShadingPoint, pixel),
                         AT(ShadingPoint, sample), AT(ShadingPoint, branch), AT(ShadingPoint, triangle),
                         AT(ShadingPoint, medium)}, sizeof(ShadingPoint)}},
  };
#undef AT
  REQUIRE(cpp.size() == dumpRecordTypes().size());
  for (const auto& [name, type] : dumpRecordTypes()) {
    INFO(name);
    REQUIRE(cpp.count(name));
    const auto& [offsets, size] = cpp.at(name);
    CHECK(type.bytes == size);
    REQUIRE(type.fields.size() == offsets.size());
    const std::vector<uint32_t> table = dumpFieldOffsets(type);
    for (size_t i = 0; i < offsets.size(); ++i) {
      INFO(type.fields[i].name);
      CHECK(table[i] == offsets[i]);
    }
  }
}

TEST_CASE("check-dump compares photons as multisets, allowing for order and rounding", "[dump]") {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<Photon> photons(200);
  for (uint32_t i = 0; i < photons.size(); ++i)
    photons[i] = {Vec3(u(rng), u(rng), u(rng)), Rgb(u(rng), u(rng), u(rng)), uint32_t(rng()), i};
  Dirs d;
  std::vector<Photon> shuffled = photons;
  std::shuffle(shuffled.begin(), shuffled.end(), rng);
  shuffled[3].power.g = nextFloat(shuffled[3].power.g);  // one ulp: rounding
  d.write("global.photons", "Photon", photons, shuffled);
  ArrayComparison a = d.compare("global.photons");
  CHECK(a.rule == "multiset");
  CHECK(a.passed());

  // One photon's power 0.1% off: one record differs, named by its field.
  std::vector<Photon> changed = shuffled;
  changed[17].power.b *= 1.001f;
  d.write("global.photons", "Photon", photons, changed);
  a = d.compare("global.photons");
  CHECK(a.differing == 1);
  REQUIRE(a.first.size() == 1);
  CHECK(a.first[0].field.find("power[2]") == 0);
  // One photon fewer: the counts differ.
  changed.pop_back();
  d.write("global.photons", "Photon", photons, changed);
  CHECK_FALSE(d.compare("global.photons").passed());
  CHECK(d.compare("global.photons").problem.find("200 records in the reference, 199") != std::string::npos);
}

TEST_CASE("check-dump compares grids and index arrays exactly, and float arrays within the tolerance", "[dump]") {
  Dirs d;
  std::vector<uint32_t> list(64);
  for (uint32_t i = 0; i < list.size(); ++i) list[i] = i * 3;
  std::vector<uint32_t> other = list;
  other[41] = 7;
  d.write("global.photon_list", "uint32", list, other);
  ArrayComparison a = d.compare("global.photon_list");
  CHECK(a.rule == "exact");
  CHECK(a.differing == 1);
  REQUIRE(a.first.size() == 1);
  CHECK(a.first[0].index == 41);
  CHECK(a.first[0].reference == "123");
  CHECK(a.first[0].candidate == "7");

  UniformGrid g;
  g.lo = Vec3(0.5f), g.hi = Vec3(2.0f), g.cellSize = Vec3(0.25f), g.invCellSize = Vec3(4.0f), g.res = {6, 6, 6};
  g.slack = 1e-6f;
  UniformGrid h = g;
  h.slack = nextFloat(g.slack);  // within any float tolerance, but a grid is exact
  d.write("global.grid", "UniformGrid", std::vector<UniformGrid>{g}, std::vector<UniformGrid>{h});
  a = d.compare("global.grid");
  CHECK(a.differing == 1);
  REQUIRE(a.first.size() == 1);
  CHECK(a.first[0].field == "slack");

  std::vector<Rgb> light(100, Rgb(0.25f, 0.5f, 0.75f));
  std::vector<Rgb> close = light;
  close[5].g = nextFloat(nextFloat(close[5].g));
  close[6].r *= 1.000001f;
  d.write("band0.indirect", "Rgb", light, close);
  CHECK(d.compare("band0.indirect").rule == "elementwise");
  CHECK(d.compare("band0.indirect").passed());
  close[60].g *= 1.0001f;
  d.write("band0.indirect", "Rgb", light, close);
  a = d.compare("band0.indirect");
  CHECK(a.differing == 1);
  REQUIRE(a.first.size() == 1);
  CHECK(a.first[0].index == 60);
  CHECK(a.first[0].field == "rgb[1]");

  // An infinity agrees only with itself, whatever the relative tolerance.
  std::vector<Rgb> infinite = light;
  infinite[9].b = INFINITY;
  d.write("band0.indirect", "Rgb", light, infinite);
  CHECK(d.compare("band0.indirect").differing == 1);
  d.write("band0.indirect", "Rgb", infinite, infinite);
  CHECK(d.compare("band0.indirect").passed());
  // A header announcing records of 0 bytes is refused, not divided by.
  writeDump(d.candidate.path.string(), "band0.indirect", "Rgb", light.data(), 0, 5);
  CHECK_THROWS_WITH(compareDumpDirectories(d.reference.path.string(), d.candidate.path.string()),
                    Catch::Contains("records of 0 bytes"));
  d.write("band0.indirect", "Rgb", light, light);

  // Another record type under the same name is not compared record by record.
  d.write("band0.direct", "Rgb", light, light);
  const std::vector<float> floats(300, 0.5f);
  writeDump(d.candidate.path.string(), "band0.direct", "float", std::span(floats));
  CHECK(d.compare("band0.direct").problem.find("record type float") == 0);
  // An array only one side holds is listed, not compared.
  writeDump(d.reference.path.string(), "caustic.photon_list", "uint32", std::span(list));
  const DumpComparison all = compareDumpDirectories(d.reference.path.string(), d.candidate.path.string());
  CHECK(all.onlyInReference == std::vector<std::string>{"caustic.photon_list"});
  CHECK_FALSE(all.passed());
}

TEST_CASE("check-dump compares kNN results as sets, allowing for ties at the radius", "[dump]") {
  // Query 0: photons 4, 9, 2 inside, 5 and 8 tied at the farthest distance; query 1: none.
  const std::vector<PhotonDistance> reference = {{0.1f, 4}, {0.3f, 9}, {0.2f, 2}, {0.5f, 5}, {0.5f, 8}};
  const std::vector<uint64_t> offsets = {0, 5, 5};
  Dirs d;
  auto write = [&](const std::vector<PhotonDistance>& candidate, const std::vector<uint64_t>& candidateOffsets) {
    d.write("band0.global.neighbours", "PhotonDistance", reference, candidate);
    d.write("band0.global.neighbour_offsets", "uint64", offsets, candidateOffsets);
    return d.compare("band0.global.neighbours");
  };
  // In another order: the same set.
  ArrayComparison a = write({{0.5f, 8}, {0.2f, 2}, {0.1f, 4}, {0.5f, 5}, {0.3f, 9}}, offsets);
  CHECK(a.rule == "neighbour sets");
  CHECK(a.passed());
  // An exact-k search that kept one of the tied photons: allowed.
  CHECK(write({{0.1f, 4}, {0.2f, 2}, {0.3f, 9}, {0.5f, 8}}, {0, 4, 4}).passed());
  // A photon inside the radius missing, or another photon in its place: query 0 differs.
  for (const auto& candidate : {std::vector<PhotonDistance>{{0.1f, 4}, {0.2f, 2}, {0.5f, 5}, {0.5f, 8}},
                                std::vector<PhotonDistance>{{0.1f, 4}, {0.2f, 2}, {0.3f, 11}, {0.5f, 5}, {0.5f, 8}}}) {
    a = write(candidate, {0, candidate.size(), candidate.size()});
    CHECK(a.differing == 1);
    REQUIRE(a.first.size() == 1);
    CHECK(a.first[0].index == 0);
  }
  // A photon inside listed twice in place of another: query 0 differs.
  a = write({{0.1f, 4}, {0.1f, 4}, {0.3f, 9}, {0.5f, 5}, {0.5f, 8}}, offsets);
  CHECK(a.differing == 1);
  // Offsets that are not uint64, or do not cut the neighbours: refused.
  d.write("band0.global.neighbour_offsets", "float", std::vector<float>{0, 5, 5}, std::vector<float>{0, 5, 5});
  CHECK(d.compare("band0.global.neighbours").problem.find("not a uint64 array") != std::string::npos);
  CHECK(write(reference, {0, 9, 5}).problem.find("are not offsets") != std::string::npos);
  // A photon where the reference found none: query 1 differs.
  a = write({{0.1f, 4}, {0.3f, 9}, {0.2f, 2}, {0.5f, 5}, {0.5f, 8}, {0.7f, 1}}, {0, 5, 6});
  CHECK(a.differing == 1);
  REQUIRE(a.first.size() == 1);
  CHECK(a.first[0].index == 1);
}

TEST_CASE("check-dump compares the environment paper's node tree by its structure, whatever its numbering", "[dump]") {
  // Root 1 with children 2 (leaf) and 3, whose children 4 and 5 are leaves; the candidate numbers
  // the same tree 1, 5, 4, 3, 2.
  auto node = [](float x, uint32_t c0, uint32_t c1, uint32_t selection) {
    EnvPointNode n;
    n.position = Vec3(x, 0, 0), n.radius = 1, n.normal = Vec3(0, 0, 1), n.coneAngle = 0.5f;
    n.child[0] = c0, n.child[1] = c1, n.selection = selection;
    return n;
  };
  const std::vector<EnvPointNode> reference = {node(0, 0, 0, 0), node(1, 2, 3, 0), node(2, 0, 0, 1), node(3, 4, 5, 2),
                                               node(4, 0, 0, 4), node(5, 0, 0, 4)};
  std::vector<EnvPointNode> candidate = {node(0, 0, 0, 0), node(1, 5, 4, 0), node(5, 0, 0, 4), node(4, 0, 0, 4),
                                         node(3, 3, 2, 2), node(2, 0, 0, 1)};
  Dirs d;
  d.write("envpbgi.nodes", "EnvPointNode", reference, candidate);
  ArrayComparison a = d.compare("envpbgi.nodes");
  CHECK(a.rule == "tree");
  CHECK(a.passed());
  // Another cut: node 4 (the candidate's 3) selected otherwise.
  candidate[3].selection = 1;
  d.write("envpbgi.nodes", "EnvPointNode", reference, candidate);
  a = d.compare("envpbgi.nodes");
  CHECK(a.differing == 1);
  REQUIRE(a.first.size() == 1);
  CHECK(a.first[0].index == 4);
  CHECK(a.first[0].field == "selection");
  // Another shape: the candidate's leaf 5 given children.
  candidate[3].selection = 4;
  candidate[5].child[0] = 2, candidate[5].child[1] = 3;
  d.write("envpbgi.nodes", "EnvPointNode", reference, candidate);
  a = d.compare("envpbgi.nodes");
  CHECK(a.differing == 1);
  REQUIRE(a.first.size() == 1);
  CHECK(a.first[0].index == 2);
  CHECK(a.first[0].field == "child");
  // A damaged candidate whose leaf points back at the root: refused, not walked for ever.
  candidate[5].child[0] = 1, candidate[5].child[1] = 2;
  candidate[4].child[0] = 5, candidate[4].child[1] = 3;
  d.write("envpbgi.nodes", "EnvPointNode", reference, candidate);
  CHECK(d.compare("envpbgi.nodes").problem == "not a tree: a node is reached twice");
}

TEST_CASE("lucent check-dump passes a render's dump against another thread count's and fails a changed one",
          "[dump][cli]") {
  TempDir a("check-dump-a"), b("check-dump-b");
  const std::string render = "render " LUCENT_SOURCE_DIR "/scenes/cornell-box.json --method purcell --map sort "
                             "--resolution 32x32 --photons 4000 --quiet --dump ";
  REQUIRE(test::runLucent(render + a.path.string() + " -o " + (a / "image.exr")).status == 0);
  REQUIRE(test::runLucent(render + b.path.string() + " --threads 1 -o " + (b / "image.exr")).status == 0);
  test::CliRun run = test::runLucent("check-dump " + a.path.string() + " " + b.path.string());
  CHECK(run.status == 0);
  CHECK(run.output.find("\"passed\":true") != std::string::npos);
  CHECK(run.output.find("band0.global.neighbours") != std::string::npos);

  auto indirect = readDump<Rgb>(b / "band0.indirect.bin", "Rgb");
  indirect[10].r += 1;
  writeDump(b.path.string(), "band0.indirect", "Rgb", std::span(indirect));
  run = test::runLucent("check-dump " + a.path.string() + " " + b.path.string());
  CHECK(run.status == 1);
  CHECK(run.output.find("band0.indirect (Rgb, elementwise): 1 of") != std::string::npos);
  // The record is named by the query it stands for: its shading point's pixel, sample and branch.
  const auto points = readDump<ShadingPoint>(a / "band0.shading_points.bin", "ShadingPoint");
  const std::string where = "shading point 10: pixel (" + std::to_string(points[10].pixel % 32) + ", " +
                            std::to_string(points[10].pixel / 32) + "), sample " + std::to_string(points[10].sample) +
                            ", branch " + std::to_string(points[10].branch);
  INFO(run.output);
  CHECK(run.output.find("record 10 (" + where + ") rgb[0]: ") != std::string::npos);
  CHECK(run.output.find(std::to_string(indirect[10].r).substr(0, 5)) != std::string::npos);  // the changed value
  CHECK(run.output.find("\"where\":\"" + where + "\"") != std::string::npos);
  // A grid's per-cell array names the cell.
  auto firstPhoton = readDump<uint32_t>(b / "global.first_photon.bin", "uint32");
  const auto grid = readDump<UniformGrid>(a / "global.grid.bin", "UniformGrid");
  REQUIRE(grid.size() == 1);
  const uint32_t cell = uint32_t(firstPhoton.size() / 2);
  firstPhoton[cell] += 1;
  writeDump(b.path.string(), "global.first_photon", "uint32", std::span(firstPhoton));
  run = test::runLucent("check-dump " + a.path.string() + " " + b.path.string());
  const uint32_t x = cell % uint32_t(grid[0].res[0]), y = cell / uint32_t(grid[0].res[0]) % uint32_t(grid[0].res[1]),
                 z = cell / uint32_t(grid[0].res[0] * grid[0].res[1]);
  INFO(run.output);
  CHECK(run.output.find("record " + std::to_string(cell) + " (cell (" + std::to_string(x) + ", " + std::to_string(y) +
                        ", " + std::to_string(z) + ")) value: ") != std::string::npos);

  CHECK(test::runLucent("check-dump " + a.path.string() + " " + (a / "missing")).status == 2);
}
