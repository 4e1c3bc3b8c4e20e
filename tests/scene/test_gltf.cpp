// glTF import (src/scene/gltf_import.cpp): a real exporter's Cornell box against the OBJ scene it was
// made from, node transforms and instancing against positions worked out by hand, the accessor
// forms (strides, normalized integers, sparse substitutions, strips and fans), and bad files refused
// with the JSON path of what is wrong.
#include <catch2/catch.hpp>
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <tuple>
#include <zlib.h>
#include <nlohmann/json.hpp>

#include "lucent/core/rng.h"
#include "lucent/image/image.h"
#include "lucent/image/metrics.h"
#include "lucent/image/noise_tests.h"
#include "lucent/methods/pathtrace.h"
#include "lucent/scene/surface.h"
#include "lucent/scene/texture.h"
#include "lucent/scene/loader.h"
#include "lucent/trace/visibility.h"
#include "test_support.h"

using namespace lucent;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

// A triangle as three corner positions, rotated to start at its smallest corner (same winding).
using Corners = std::array<Vec3, 3>;
bool before(Vec3 a, Vec3 b) { return a.x != b.x ? a.x < b.x : a.y != b.y ? a.y < b.y : a.z < b.z; }
std::vector<Corners> triangles(const Scene& s, const std::string& material = "") {
  std::vector<Corners> out;
  for (uint32_t t = 0; t < s.triangleCount(); ++t) {
    if (!material.empty() && s.materialNames[s.materialIds[t]] != material) continue;
    Corners c{s.vertex(t, 0), s.vertex(t, 1), s.vertex(t, 2)};
    std::rotate(c.begin(), std::min_element(c.begin(), c.end(), before), c.end());
    out.push_back(c);
  }
  std::sort(out.begin(), out.end(), [](const Corners& a, const Corners& b) { return before(a[0], b[0]) || (a[0] == b[0] && before(a[1], b[1])); });
  return out;
}
bool near(Vec3 a, Vec3 b, float tolerance) { return length(a - b) <= tolerance; }

std::string base64(const std::vector<unsigned char>& bytes) {
  static const char* digits = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (size_t i = 0; i < bytes.size(); i += 3) {
    const uint32_t n = uint32_t(bytes[i]) << 16 | (i + 1 < bytes.size() ? uint32_t(bytes[i + 1]) << 8 : 0) |
                       (i + 2 < bytes.size() ? bytes[i + 2] : 0);
    out += digits[n >> 18 & 63];
    out += digits[n >> 12 & 63];
    out += i + 1 < bytes.size() ? digits[n >> 6 & 63] : '=';
    out += i + 2 < bytes.size() ? digits[n & 63] : '=';
  }
  return out;
}
template <class T>
void append(std::vector<unsigned char>& bytes, T value) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, &value, sizeof(T));
  bytes.insert(bytes.end(), b, b + sizeof(T));
}

// A glTF file with one buffer (a data URI) and the given JSON around it: a unit quad in the xy
// plane, its positions and normals interleaved (stride 24), its texture coordinates as normalized
// bytes, a triangle strip of unsigned short indices; one Lambertian material and one point light.
// The quad's buffer: positions and normals interleaved, texture coordinates, strip indices; the
// first position's x replaced by `firstX` (a NaN for the broken-file test).
std::vector<unsigned char> quadBuffer(float firstX = 0) {
  std::vector<unsigned char> b;
  const float corners[4][2] = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
  for (const auto& c : corners) {
    for (const float v : {&c == &corners[0] ? firstX : c[0], c[1], 0.0f}) append(b, v);
    for (const float v : {0.0f, 0.0f, 1.0f}) append(b, v);
  }
  for (const auto& c : corners) append(b, uint8_t(c[0] * 255)), append(b, uint8_t(c[1] * 255));
  for (const uint16_t i : {0, 1, 2, 3}) append(b, i);
  return b;
}

json quadFile(const std::vector<json>& nodes, const std::vector<int>& roots) {
  const std::vector<unsigned char> b = quadBuffer();
  json f;
  f["asset"] = {{"version", "2.0"}};
  f["buffers"] = {{{"byteLength", b.size()}, {"uri", "data:application/octet-stream;base64," + base64(b)}}};
  f["bufferViews"] = {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 96}, {"byteStride", 24}},
                      {{"buffer", 0}, {"byteOffset", 96}, {"byteLength", 8}},
                      {{"buffer", 0}, {"byteOffset", 104}, {"byteLength", 8}}};
  f["accessors"] = {{{"bufferView", 0}, {"byteOffset", 0}, {"componentType", 5126}, {"count", 4}, {"type", "VEC3"},
                     {"min", {0, 0, 0}}, {"max", {1, 1, 0}}},
                    {{"bufferView", 0}, {"byteOffset", 12}, {"componentType", 5126}, {"count", 4}, {"type", "VEC3"}},
                    {{"bufferView", 1}, {"componentType", 5121}, {"normalized", true}, {"count", 4}, {"type", "VEC2"}},
                    {{"bufferView", 2}, {"componentType", 5123}, {"count", 4}, {"type", "SCALAR"}}};
  f["materials"] = {{{"name", "grey"},
                     {"pbrMetallicRoughness", {{"baseColorFactor", {0.5, 0.5, 0.5, 1}}, {"metallicFactor", 0}}},
                     {"extensions", {{"KHR_materials_specular", {{"specularFactor", 0}}}}}}};
  f["meshes"] = {{{"primitives", {{{"attributes", {{"POSITION", 0}, {"NORMAL", 1}, {"TEXCOORD_0", 2}}},
                                   {"indices", 3}, {"material", 0}, {"mode", 5}}}}}};
  f["extensionsUsed"] = {"KHR_lights_punctual", "KHR_materials_specular"};
  f["extensions"] = {{"KHR_lights_punctual", {{"lights", {{{"type", "point"}, {"intensity", 683}}}}}}};
  json allNodes = nodes;
  allNodes.push_back({{"translation", {0, 5, 0}}, {"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}});
  f["nodes"] = allNodes;
  json sceneRoots = roots;
  sceneRoots.push_back(int(nodes.size()));
  f["scenes"] = {{{"nodes", sceneRoots}}};
  f["scene"] = 0;
  return f;
}

std::string writeFile(const fs::path& dir, const std::string& name, const json& f) {
  const fs::path p = dir / name;
  std::ofstream(p) << f.dump();
  return p.string();
}

// An 8-bit RGBA PNG of the given codes (alpha unassociated: stored beside the colour, as PNG
// stores it), in memory: the signature, IHDR, one IDAT of the rows (each after filter type 0)
// deflated by zlib, IEND; each chunk with its CRC-32.
std::vector<unsigned char> rgbaPng(int width, int height, const std::vector<unsigned char>& rgba) {
  const auto bigEndian = [](std::vector<unsigned char>& out, uint32_t v) {
    for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<unsigned char>(v >> shift));
  };
  std::vector<unsigned char> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  auto chunk = [&](const char* type, const std::vector<unsigned char>& data) {
    bigEndian(png, uint32_t(data.size()));
    const size_t start = png.size();
    png.insert(png.end(), type, type + 4);
    png.insert(png.end(), data.begin(), data.end());
    bigEndian(png, uint32_t(crc32(0, png.data() + start, uInt(png.size() - start))));
  };
  std::vector<unsigned char> header;
  bigEndian(header, uint32_t(width));
  bigEndian(header, uint32_t(height));
  header.insert(header.end(), {8, 6, 0, 0, 0});  // 8 bits, RGBA, deflate, filters, no interlace
  chunk("IHDR", header);
  std::vector<unsigned char> rows;
  for (int y = 0; y < height; ++y) {
    rows.push_back(0);
    rows.insert(rows.end(), rgba.begin() + ptrdiff_t(y) * width * 4, rgba.begin() + ptrdiff_t(y + 1) * width * 4);
  }
  uLongf deflatedSize = compressBound(uLong(rows.size()));
  std::vector<unsigned char> deflated(deflatedSize);
  REQUIRE(compress(deflated.data(), &deflatedSize, rows.data(), uLong(rows.size())) == Z_OK);
  deflated.resize(deflatedSize);
  chunk("IDAT", deflated);
  chunk("IEND", {});
  return png;
}

// A scene file around a glTF file (the camera is the scene file's): its path.
std::string wrapGltf(const fs::path& dir, const json& gltf) {
  const std::string file = writeFile(dir, "model.gltf", gltf);
  json scene = {{"camera", {{"eye", {0, 0, 10}}, {"look_at", {0, 0, 0}}, {"up", {0, 1, 0}}, {"fov_y", 40}, {"resolution", {8, 8}}}},
                {"meshes", {{{"gltf", file}}}}};
  return writeFile(dir, "scene.json", scene);
}
Scene loadWrapped(const fs::path& dir, const json& gltf, bool quiet = true) {
  return loadScene(wrapGltf(dir, gltf), LoadOptions(quiet));
}

// The `ignored` list in the JSON line of a small render of scene `file` by `method` (pmfg, micro),
// one entry per line.
std::string ignoredBy(const std::string& method, const std::string& file, const std::string& exr) {
  const std::string options = method == "pmfg" ? " --photons 1000 --gather-rays 4" : "";
  const test::CliRun r =
      test::runLucent("render " + file + " --method " + method + options + " --spp 1 --resolution 8x8 -q -o " + exr);
  INFO(r.output);
  REQUIRE(r.status == 0);
  const json line = json::parse(r.output.substr(r.output.find('{')));
  std::string list;
  for (const json& entry : line.value("ignored", json::array())) list += entry.get<std::string>() + "\n";
  return list;
}

// A 2 x 1 texture's sRGB codes, and the PNG of them that Lucent's encoder writes from their linear
// values.
constexpr uint8_t kTexelCodes[2][3] = {{200, 30, 90}, {12, 250, 128}};
std::vector<unsigned char> texelCodesPng() {
  Image image(2, 1, {"R", "G", "B"});
  for (int x = 0; x < 2; ++x)
    for (int c = 0; c < 3; ++c) image.at(x, 0, c) = kSrgb8ToLinear[kTexelCodes[x][c]];
  return encodePng(image);
}

// The quad with an occlusion texture, which renders leave out and list.
json quadWithOcclusion() {
  json f = quadFile({{{"mesh", 0}}}, {0});
  f["materials"][0]["occlusionTexture"] = {{"index", 0}};
  f["textures"] = {{{"source", 0}}};
  f["images"] = {{{"uri", "data:image/png;base64," + base64(encodePng(Image(1, 1, {"R", "G", "B"})))}}};
  return f;
}

}  // namespace

TEST_CASE("The Cornell box as Blender's glTF exporter writes it loads as the OBJ scene it came from", "[gltf][loader]") {
  const Scene gltf = loadScene(LUCENT_SOURCE_DIR "/scenes/gltf/cornell-box.glb", {true});
  const Scene obj = loadScene(LUCENT_SOURCE_DIR "/scenes/cornell-box.json", {true});
  // The same triangles of each material (to float rounding after the node's rotation), the same
  // reflectances and emission, the same camera.
  for (const auto& [name, kd, ke] : {std::tuple{"white", Rgb(0.725f, 0.71f, 0.68f), Rgb(0.0f)},
                                     std::tuple{"red", Rgb(0.63f, 0.065f, 0.05f), Rgb(0.0f)},
                                     std::tuple{"green", Rgb(0.14f, 0.45f, 0.091f), Rgb(0.0f)},
                                     std::tuple{"light", Rgb(0.0f), Rgb(17, 12, 4)}}) {
    INFO(name);
    const auto a = triangles(gltf, name), b = triangles(obj, name);
    REQUIRE(a.size() == b.size());
    REQUIRE(!a.empty());
    // The OBJ splits its quads along other diagonals than Blender does: compare the corner sets.
    std::vector<Vec3> ca, cb;
    for (const auto& t : a) ca.insert(ca.end(), t.begin(), t.end());
    for (const auto& t : b) cb.insert(cb.end(), t.begin(), t.end());
    for (const Vec3 p : ca)
      CHECK(std::any_of(cb.begin(), cb.end(), [&](Vec3 q) { return near(p, q, 1e-3f); }));
    const auto material = [&](const Scene& s) {
      const auto it = std::find(s.materialNames.begin(), s.materialNames.end(), name);
      REQUIRE(it != s.materialNames.end());
      return s.materials[size_t(it - s.materialNames.begin())];
    };
    const Material ma = material(gltf), mb = material(obj);
    // Blender writes its Specular 0 as specularColorFactor 0 beside the default specularFactor 1
    // and ior 1.45: a dielectric of F0 0 and F90 1 (a Fresnel lobe at grazing angles), roughness 1.
    CHECK(ma.type == MaterialType::Gltf);
    CHECK(ma.metallic == 0.0f);
    CHECK(ma.roughness == 1.0f);
    CHECK(ma.specular == 1.0f);
    CHECK(ma.ni == Approx(1.45f));
    for (int c = 0; c < 3; ++c) {
      CHECK(ma.ks[c] == 0.0f);
      CHECK(ma.kd[c] == Approx(mb.kd[c]).margin(1e-6));
      CHECK(ma.ke[c] == Approx(mb.ke[c]).epsilon(1e-6));
    }
  }
  CHECK(gltf.surfaceArea() == Approx(obj.surfaceArea()).epsilon(1e-6));
  CHECK(near(gltf.camera.eye, obj.camera.eye, 1e-3f));
  CHECK(near(normalize(gltf.camera.lookAt - gltf.camera.eye), normalize(obj.camera.lookAt - obj.camera.eye), 1e-6f));
  CHECK(gltf.camera.fovY == Approx(obj.camera.fovY).epsilon(1e-5));
  CHECK(gltf.camera.width == 512);
  CHECK(gltf.camera.height == 512);
  // Nothing is left out; the light is doubleSided (Blender's default), so its back face emits too.
  CHECK(gltf.ignored.empty());
  const auto light = std::find(gltf.materialNames.begin(), gltf.materialNames.end(), "light");
  REQUIRE(light != gltf.materialNames.end());
  CHECK(gltf.materials[size_t(light - gltf.materialNames.begin())].emitsBackFace == 1);
}

TEST_CASE("The exported Cornell box renders as the OBJ scene within noise once Lambertian, as exported its "
          "grazing Fresnel lobe shows",
          "[gltf][cli]") {
  const test::TempDir dir;
  // 256 independent samples at 64 x 64 with their variance; each image tested against the OBJ scene's.
  const auto render = [&](const std::string& scene, int seed) {
    const std::string exr = dir / ("image" + std::to_string(seed) + ".exr");
    const test::CliRun r = test::runLucent("render " + std::string(LUCENT_SOURCE_DIR) + "/scenes/" + scene +
                                           " --resolution 64x64 --spp 256 --sampler independent --variance -q --seed " +
                                           std::to_string(seed) + " -o " + exr);
    INFO(r.output);
    REQUIRE(r.status == 0);
    return readImage(exr);
  };
  const Image reference = render("cornell-box.json", 1);
  const NoiseTest lambertian = testWithinNoise(render("gltf/cornell-box-diffuse.json", 2), reference, 0.01);
  CHECK(lambertian.verdict == Verdict::Pass);
  CHECK(lambertian.blocksRejected == 0);
  // As exported: F0 0 and F90 1 (Blender's Specular 0), whose lobe shows near the walls' grazing
  // views, and a doubleSided light whose back face's light escapes from the 0.8 mm gap below the
  // ceiling (the image 2.4% brighter).
  const NoiseTest exported = testWithinNoise(render("gltf/cornell-box.glb", 3), reference, 0.01);
  CHECK(exported.verdict == Verdict::Fail);
}

TEST_CASE("glTF nodes place, rotate, scale, mirror and instance meshes as worked out by hand", "[gltf][loader]") {
  const test::TempDir dir;
  // Node 0: the quad moved by (1, 2, 3). Node 1: turned 90 degrees about z, scaled 2 along x, with
  // child node 2 (the quad again, a second instance) moved by (0, 0, 5) in node 1's frame by a
  // matrix. Node 3: the quad mirrored in x (scale -1): its winding turns over to stay
  // counter-clockwise seen from its normal's side.
  const double s = std::sqrt(0.5);
  const json nodes = {{{"mesh", 0}, {"translation", {1, 2, 3}}},
                      {{"rotation", {0, 0, s, s}}, {"scale", {2, 1, 1}}, {"children", {2}}},
                      {{"mesh", 0}, {"matrix", {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 5, 1}}},
                      {{"mesh", 0}, {"scale", {-1, 1, 1}}}};
  const Scene scene = loadWrapped(dir.path, quadFile(nodes, {0, 1, 3}));
  REQUIRE(scene.triangleCount() == 6);  // a strip of 4 indices: 2 triangles per instance
  // Corners of the unit quad, by hand: node 0 adds (1, 2, 3); node 2 in node 1 maps (x, y, z) to
  // R_z(90)(2x, y, z + 5) = (-y, 2x, z + 5); node 3 maps to (-x, y, z).
  const auto expect = [&](uint32_t firstTriangle, auto place, Vec3 normal) {
    std::vector<Vec3> got;
    for (uint32_t t = firstTriangle; t < firstTriangle + 2; ++t) {
      for (int k = 0; k < 3; ++k) got.push_back(scene.vertex(t, k));
      // Counter-clockwise about the transformed normal, and the vertex normals turned alike.
      CHECK(near(scene.geometricNormal(t), normal, 1e-6f));
      for (int k = 0; k < 3; ++k) CHECK(near(scene.normals[scene.indices[3 * t + k]], normal, 1e-6f));
    }
    for (const Vec3 corner : {Vec3{0, 0, 0}, Vec3{1, 0, 0}, Vec3{0, 1, 0}, Vec3{1, 1, 0}})
      CHECK(std::any_of(got.begin(), got.end(), [&](Vec3 p) { return near(p, place(corner), 1e-6f); }));
  };
  expect(0, [](Vec3 p) { return p + Vec3{1, 2, 3}; }, {0, 0, 1});
  expect(2, [](Vec3 p) { return Vec3{-p.y, 2 * p.x, p.z + 5}; }, {0, 0, 1});
  expect(4, [](Vec3 p) { return Vec3{-p.x, p.y, p.z}; }, {0, 0, 1});
  // Texture coordinates: normalized bytes, v turned to run up.
  CHECK(scene.texcoords[scene.indices[0]].x == Approx(0.0));
  CHECK(scene.texcoords[scene.indices[0]].y == Approx(1.0));
  // The point light: 683 cd of white, 1 W/sr, at (0, 5, 0).
  REQUIRE(scene.lights.size() == 1);
  CHECK(scene.lights[0].type == LightType::Point);
  CHECK(near(scene.lights[0].vector, {0, 5, 0}, 1e-6f));
  CHECK(scene.lights[0].value.r == Approx(1.0));
  CHECK(scene.materials[0].kd.r == Approx(0.5));
  CHECK(scene.ignored.empty());  // specularFactor 0: a Lambertian material, nothing left out
}

TEST_CASE("glTF accessors: sparse substitutions, fans, unindexed triangles, and lines skipped", "[gltf][loader]") {
  const test::TempDir dir;
  json f = quadFile({{{"mesh", 0}}}, {0});
  // A fan over the same four corners, unindexed, with corner 3 moved to (2, 2, 0) by a sparse
  // substitution; a second primitive of lines, skipped and said.
  std::vector<unsigned char> b;
  append(b, uint8_t(3));
  for (const float v : {2.0f, 2.0f, 0.0f}) append(b, v);
  f["buffers"].push_back({{"byteLength", b.size()}, {"uri", "data:application/octet-stream;base64," + base64(b)}});
  f["bufferViews"].push_back({{"buffer", 1}, {"byteOffset", 0}, {"byteLength", 1}});
  f["bufferViews"].push_back({{"buffer", 1}, {"byteOffset", 1}, {"byteLength", 12}});
  f["accessors"][0]["sparse"] = {{"count", 1},
                                 {"indices", {{"bufferView", 3}, {"componentType", 5121}}},
                                 {"values", {{"bufferView", 4}}}};
  f["meshes"][0]["primitives"][0].erase("indices");
  f["meshes"][0]["primitives"][0]["mode"] = 6;
  json lines = f["meshes"][0]["primitives"][0];
  lines["mode"] = 1;
  f["meshes"][0]["primitives"].push_back(lines);
  const Scene scene = loadWrapped(dir.path, f);
  REQUIRE(scene.triangleCount() == 2);  // a fan of 4 vertices
  std::vector<Vec3> corners;
  for (uint32_t t = 0; t < 2; ++t)
    for (int k = 0; k < 3; ++k) corners.push_back(scene.vertex(t, k));
  CHECK(std::any_of(corners.begin(), corners.end(), [](Vec3 p) { return near(p, {2, 2, 0}, 0); }));
  CHECK(std::none_of(corners.begin(), corners.end(), [](Vec3 p) { return near(p, {1, 1, 0}, 0); }));
  REQUIRE(scene.ignored.size() == 1);
  CHECK_THAT(scene.ignored[0], Catch::Contains("1 point and line primitives"));
}

TEST_CASE("Broken glTF files are refused with the file and the JSON path of what is wrong", "[gltf][loader]") {
  const test::TempDir dir;
  const json good = quadFile({{{"mesh", 0}}}, {0});
  const auto refused = [&](json f, const std::string& expected) {
    INFO(expected);
    REQUIRE_THROWS_WITH(loadWrapped(dir.path, f), Catch::Contains("model.gltf") && Catch::Contains(expected));
  };
  json f = good;
  f["accessors"][3]["count"] = 40;  // more indices than the view holds
  refused(f, "accessors[3]: 40 elements of 2 bytes");
  f = good;
  f["meshes"][0]["primitives"][0]["indices"] = 9;
  refused(f, "indices accessor out of bounds");  // TinyGLTF's own check, before Lucent's
  f = good;
  f["accessors"][0]["count"] = 5;  // the view holds 4 vertices at stride 24
  refused(f, "accessors[0]: 5 elements");
  f = good;
  f["bufferViews"][0]["byteStride"] = 8;  // narrower than a VEC3 of floats
  refused(f, "bufferViews[0].byteStride: 8 is not in [12, 252]");
  f = good;
  f["bufferViews"][2]["byteLength"] = 800;  // beyond the buffer
  refused(f, "bufferViews[2]: bytes");
  f = good;
  f["nodes"][0]["children"] = {0};  // a cycle
  refused(f, "nodes[0]: is reached twice (its children lead back to it");
  f = good;
  f["scenes"][0]["nodes"].push_back(f["scenes"][0]["nodes"][0]);  // a root named twice: two instances
  refused(f, "is reached twice");
  f = good;  // a chain of nodes each naming the next twice: 2^40 instances from a few kilobytes
  for (int level = 0; level < 40; ++level) {
    const int next = int(f["nodes"].size());
    f["nodes"].push_back({{"children", {next + 1, next + 1}}});
  }
  f["nodes"].push_back({{"mesh", 0}});
  f["scenes"][0]["nodes"] = {int(f["nodes"].size()) - 41};
  refused(f, "is reached twice");
  f = good;  // 2^28 zero vectors that no buffer holds
  f["accessors"][0].erase("bufferView");
  f["accessors"][0]["count"] = 1 << 28;
  refused(f, "accessors[0].count: 268435456 elements of 12 bytes without a bufferView");
  f = good;
  f["extensionsRequired"] = {"KHR_draco_mesh_compression"};
  f["extensionsUsed"] = {"KHR_draco_mesh_compression", "KHR_lights_punctual"};
  refused(f, "extensionsRequired: names KHR_draco_mesh_compression");
  f = good;
  f["materials"][0]["pbrMetallicRoughness"]["metallicFactor"] = 1.5;
  refused(f, "materials[0].pbrMetallicRoughness.metallicFactor: must be in [0, 1]");
  f = good;
  f["materials"][0]["pbrMetallicRoughness"]["roughnessFactor"] = -0.1;
  refused(f, "materials[0].pbrMetallicRoughness.roughnessFactor: must be in [0, 1]");
  f = good;
  f["materials"][0]["extensions"]["KHR_materials_ior"]["ior"] = 0.5;
  refused(f, "materials[0].extensions.KHR_materials_ior.ior: must be 0 or in [1, 1e15]");
  f = good;
  f["materials"][0]["extensions"]["KHR_materials_specular"]["specularColorFactor"] = {1, -1, 1};
  refused(f, "materials[0].extensions.KHR_materials_specular.specularColorFactor: every value");
  f = good;
  f["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = {{"index", 0}};
  f["textures"] = {{{"source", 0}}};
  f["images"] = {{{"uri", "missing.png"}}};
  refused(f, "images[0].uri: 'missing.png' could not be read: no such file in " + dir.path.string());
  fs::create_directory(dir.path / "folder.png");
  f["images"] = {{{"uri", "folder.png"}}};
  refused(f, "images[0].uri: 'folder.png' could not be read: " + (dir.path / "folder.png").string() +
                 " is not a regular file");
  f["images"] = {{{"uri", "data:image/png;base64," + base64({'n', 'o', 't', ' ', 'a', 'n', ' ', 'i', 'm', 'a', 'g', 'e'})}}};
  refused(f, "images[0]: is neither a PNG nor a JPEG image");
  f = good;
  f["materials"][0]["emissiveTexture"] = {{"index", 0}};
  refused(f, "materials[0].emissiveTexture.index: texture 0 does not exist");
  // A NaN position (written as the bytes of a NaN: JSON has no NaN).
  f = good;
  f["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64(quadBuffer(std::nanf("")));
  refused(f, "accessors[0]: element 0 is not finite");
  // An external buffer that is not a regular file (a FIFO would block a plain read for ever).
  f = good;
  const fs::path fifo = dir.path / "buffer.bin";
  REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
  f["buffers"][0]["uri"] = "buffer.bin";
  refused(f, "not a readable glTF file");
  // A truncated binary file.
  std::ifstream in(LUCENT_SOURCE_DIR "/scenes/gltf/cornell-box.glb", std::ios::binary);
  std::string glb((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const fs::path cut = dir.path / "cut.glb";
  std::ofstream(cut, std::ios::binary) << glb.substr(0, glb.size() / 2);
  REQUIRE_THROWS_WITH(loadScene(cut.string(), {true}), Catch::Contains("cut.glb: not a readable glTF file"));
}

TEST_CASE("lucent render renders a glTF file from its camera and says what it leaves out", "[gltf][cli]") {
  const test::TempDir dir;
  const std::string exr = dir / "box.exr";
  // The exported Cornell box from its own camera: nothing left out, nothing said.
  const test::CliRun box =
      test::runLucent(std::string("render ") + LUCENT_SOURCE_DIR "/scenes/gltf/cornell-box.glb --spp 1 --resolution 16x16 -q -o " + exr);
  INFO(box.output);
  REQUIRE(box.status == 0);
  CHECK(box.output.find("\"ignored\"") == std::string::npos);
  // An occlusion texture is left out: said in the JSON line and the EXR's metadata alike.
  const test::CliRun r = test::runLucent("render " + wrapGltf(dir.path, quadWithOcclusion()) + " --spp 1 -q -o " + exr);
  INFO(r.output);
  REQUIRE(r.status == 0);
  const json line = json::parse(r.output.substr(r.output.find('{')));
  REQUIRE(line.contains("ignored"));
  REQUIRE(line["ignored"].size() == 1);
  CHECK_THAT(line["ignored"][0].get<std::string>(), Catch::Contains("occlusionTexture"));
  ImageMetadata metadata;
  readImage(exr, &metadata);
  const auto it = std::find_if(metadata.begin(), metadata.end(), [](const auto& m) { return m.first == "lucent:ignored"; });
  REQUIRE(it != metadata.end());
  CHECK(json::parse(it->second) == line["ignored"]);
  // --strict refuses it, one line per thing left out, and writes nothing.
  const std::string refusedExr = dir / "strict.exr";
  const test::CliRun strict =
      test::runLucent("render " + wrapGltf(dir.path, quadWithOcclusion()) + " --spp 1 -q --strict -o " + refusedExr);
  INFO(strict.output);
  CHECK(strict.status == 1);
  CHECK_THAT(strict.output, Catch::Contains("hold:\n  ") && Catch::Contains("occlusionTexture"));
  CHECK(strict.output.find("\\x0a") == std::string::npos);
  CHECK_FALSE(fs::exists(refusedExr));
}

TEST_CASE("lucent render --strict refuses a scene whose files hold what the render leaves out", "[gltf][cli]") {
  const test::TempDir dir;
  const std::string exr = dir / "quad.exr";
  const test::CliRun r = test::runLucent("render " + wrapGltf(dir.path, quadWithOcclusion()) + " --strict --spp 1 -q -o " + exr);
  CHECK(r.status == 1);
  CHECK_THAT(r.output, Catch::Contains("--strict: the render would leave out") && Catch::Contains("occlusionTexture"));
  CHECK(!fs::exists(exr));
  const test::CliRun plain = test::runLucent(std::string("render ") + LUCENT_SOURCE_DIR
                                             "/scenes/gltf/cornell-box.glb --strict --spp 1 --resolution 16x16 -q -o " + exr);
  CHECK(plain.status == 0);
}

TEST_CASE("KHR_materials_transmission: read with its texture's R, rendered by pt, pmfg and purcell, listed as "
          "left out by the point-based methods",
          "[gltf][loader][cli]") {
  const test::TempDir dir;
  json f = quadFile({{{"mesh", 0}}}, {0});
  f["extensionsUsed"] = {"KHR_materials_transmission"};
  f["images"] = {{{"uri", "data:image/png;base64," + base64(rgbaPng(1, 1, {153, 0, 0, 255}))}}};
  f["textures"] = {{{"source", 0}}};
  f["materials"][0]["extensions"]["KHR_materials_transmission"] = {{"transmissionFactor", 0.5},
                                                                   {"transmissionTexture", {{"index", 0}}}};
  const Scene scene = loadWrapped(dir.path, f);
  CHECK(scene.ignored.empty());
  const SurfaceBsdf b = bsdfAt(scene, surfaceAt(scene, 0, 0.25f, 0.25f));
  CHECK(b.gltf.transmission == Approx(0.5 * 153 / 255.0).epsilon(1e-5));
  CHECK(has(b.flags(), BsdfFlags::Transmission));
  f["materials"][0]["extensions"]["KHR_materials_transmission"] = {{"transmissionFactor", 1.5}};
  REQUIRE_THROWS_WITH(loadWrapped(dir.path, f),
                      Catch::Contains("materials[0].extensions.KHR_materials_transmission.transmissionFactor: must be in [0, 1]"));
  // pt and the photon maps render it; micro (as the other point-based methods) says what it leaves
  // out, and --strict refuses it.
  f["materials"][0]["extensions"]["KHR_materials_transmission"] = {{"transmissionFactor", 0.5}};
  const std::string file = wrapGltf(dir.path, f), exr = dir / "quad.exr";
  const test::CliRun pt = test::runLucent("render " + file + " --spp 1 --resolution 8x8 -q --strict -o " + exr);
  INFO(pt.output);
  CHECK(pt.status == 0);
  CHECK(pt.output.find("\"ignored\"") == std::string::npos);
  CHECK(ignoredBy("pmfg", file, exr).empty());
  CHECK_THAT(ignoredBy("micro", file, exr), Catch::Contains("KHR_materials_transmission") && Catch::Contains("micro"));
  fs::remove(exr);
  const test::CliRun strict = test::runLucent("render " + file + " --method micro --spp 1 --resolution 8x8 -q --strict -o " + exr);
  CHECK(strict.status == 1);
  CHECK_THAT(strict.output, Catch::Contains("--strict") && Catch::Contains("KHR_materials_transmission"));
  CHECK_FALSE(fs::exists(exr));
}

TEST_CASE("KHR_materials_volume: a thickness above 0 with transmission bounds a medium of the material's index and "
          "attenuation, its thickness texture left to rasterizers",
          "[gltf][loader][cli]") {
  const test::TempDir dir;
  json f = quadFile({{{"mesh", 0}}}, {0});
  f["extensionsUsed"] = {"KHR_materials_transmission", "KHR_materials_volume", "KHR_materials_ior"};
  f["images"] = {{{"uri", "data:image/png;base64," + base64(rgbaPng(1, 1, {153, 0, 0, 255}))}}};
  f["textures"] = {{{"source", 0}}};
  f["materials"][0]["extensions"]["KHR_materials_transmission"] = {{"transmissionFactor", 1}};
  f["materials"][0]["extensions"]["KHR_materials_ior"] = {{"ior", 1.33}};
  f["materials"][0]["extensions"]["KHR_materials_volume"] = {{"thicknessFactor", 0.2},
                                                             {"thicknessTexture", {{"index", 0}}},
                                                             {"attenuationDistance", 0.5},
                                                             {"attenuationColor", {0.9, 0.5, 0.25}}};
  Scene scene = loadWrapped(dir.path, f);
  CHECK(scene.ignored.empty());
  const Material& m = scene.materials[0];
  CHECK(m.boundsVolume == 1);
  CHECK(m.culledBehind == 0);  // doubleSided has no effect on a volume's boundary
  CHECK(m.attenuationDistance == 0.5f);
  CHECK(m.attenuationColour.b == 0.25f);
  CHECK(mediumTransmittance(m, 1.0f).b == Approx(0.0625f));
  SurfaceBsdf b = bsdfAt(scene, surfaceAt(scene, 0, 0.25f, 0.25f));
  CHECK(b.gltf.volumeIor == 1.33f);
  CHECK(!has(b.flags(), BsdfFlags::TwoSided));
  // The defaults: no attenuation; without transmission, or at index 0, nothing enters: a thin wall.
  f["materials"][0]["extensions"]["KHR_materials_volume"] = {{"thicknessFactor", 1}};
  scene = loadWrapped(dir.path, f);
  CHECK(scene.materials[0].boundsVolume == 1);
  CHECK(mediumTransmittance(scene.materials[0], 1e30f).g == 1.0f);
  f["materials"][0]["extensions"]["KHR_materials_ior"] = {{"ior", 0}};
  CHECK(loadWrapped(dir.path, f).materials[0].boundsVolume == 0);
  f["materials"][0]["extensions"]["KHR_materials_ior"] = {{"ior", 1.33}};
  f["materials"][0]["extensions"]["KHR_materials_transmission"] = {{"transmissionFactor", 0}};
  CHECK(loadWrapped(dir.path, f).materials[0].boundsVolume == 0);
  f["materials"][0]["extensions"]["KHR_materials_transmission"] = {{"transmissionFactor", 1}};
  f["materials"][0]["extensions"]["KHR_materials_volume"] = {{"thicknessFactor", 0}};
  scene = loadWrapped(dir.path, f);
  CHECK(scene.materials[0].boundsVolume == 0);
  CHECK(scene.materials[0].culledBehind == 1);
  CHECK(has(bsdfAt(scene, surfaceAt(scene, 0, 0.25f, 0.25f)).flags(), BsdfFlags::TwoSided));
  for (const auto& [field, value, message] :
       {std::tuple<const char*, json, const char*>{"thicknessFactor", -1, "thicknessFactor: must be in [0, 1e15]"},
        {"attenuationDistance", 0, "attenuationDistance: must be above 0"},
        {"attenuationColor", json{1.5, 0, 0}, "attenuationColor: every value must be in [0, 1]"},
        {"thicknessTexture", json{{"texCoord", 0}}, "thicknessTexture.index: is required"}}) {
    f["materials"][0]["extensions"]["KHR_materials_volume"] = {{"thicknessFactor", 1}};
    f["materials"][0]["extensions"]["KHR_materials_volume"][field] = value;
    INFO(field);
    REQUIRE_THROWS_WITH(loadWrapped(dir.path, f),
                        Catch::Contains(std::string("materials[0].extensions.KHR_materials_volume.") + message));
  }
  // pmfg renders the boundary and the medium's attenuation; micro the light through it in part.
  f["materials"][0]["extensions"]["KHR_materials_volume"] = {
      {"thicknessFactor", 1}, {"attenuationDistance", 2}, {"attenuationColor", {0.5, 0.5, 0.5}}};
  const std::string file = wrapGltf(dir.path, f), exr = dir / "quad.exr";
  CHECK(ignoredBy("pmfg", file, exr).empty());
  CHECK(ignoredBy("purcell", file, exr).empty());
  CHECK_THAT(ignoredBy("micro", file, exr), Catch::Contains("KHR_materials_transmission") && Catch::Contains("in part"));
}

TEST_CASE("A closed glTF volume of single-sided faces under a constant sky vanishes: light enters, refracts and "
          "leaves through its back faces",
          "[gltf][pathtrace][furnace]") {
  // Six of quadFile's unit quads turned into a cube, each facing out, doubleSided false; a white
  // lossless boundary of index 1.5 (the white furnace: every microfacet reflects F and passes 1 - F).
  // Culling the back faces inside would let light leave unrefracted, 1 / 1.5^2 of it.
  const test::TempDir dir;
  const double h = std::sqrt(0.5);
  json f = quadFile({{{"mesh", 0}, {"translation", {0, 0, 1}}},
                     {{"mesh", 0}, {"translation", {1, 0, 0}}, {"rotation", {0, 1, 0, 0}}},
                     {{"mesh", 0}, {"translation", {1, 0, 1}}, {"rotation", {0, h, 0, h}}},
                     {{"mesh", 0}, {"rotation", {0, -h, 0, h}}},
                     {{"mesh", 0}, {"translation", {0, 1, 1}}, {"rotation", {-h, 0, 0, h}}},
                     {{"mesh", 0}, {"rotation", {h, 0, 0, h}}}},
                    {0, 1, 2, 3, 4, 5});
  f["nodes"].erase(6);  // the point light
  f["scenes"][0]["nodes"] = {0, 1, 2, 3, 4, 5};
  f.erase("extensions");
  f["extensionsUsed"] = {"KHR_materials_transmission", "KHR_materials_volume"};
  f["materials"][0] = {{"name", "glass"},
                       {"pbrMetallicRoughness", {{"baseColorFactor", {1, 1, 1, 1}}, {"metallicFactor", 0},
                                                 {"roughnessFactor", 0.1}}},
                       {"extensions", {{"KHR_materials_transmission", {{"transmissionFactor", 1}}},
                                       {"KHR_materials_volume", {{"thicknessFactor", 1}}}}}};
  const std::string model = writeFile(dir.path, "model.gltf", f);
  const json sceneFile = {{"camera", {{"eye", {2.2, 1.9, 2.6}}, {"look_at", {0.5, 0.5, 0.5}}, {"up", {0, 1, 0}},
                                      {"fov_y", 30}, {"resolution", {24, 24}}}},
                          {"meshes", {{{"gltf", model}}}},
                          {"lights", {{{"type", "environment"}, {"radiance", {0.5, 1.0, 2.0}}}}}};
  const Scene scene = loadScene(writeFile(dir.path, "scene.json", sceneFile), LoadOptions(true));
  REQUIRE(scene.ignored.empty());
  const Visibility vis(scene);
  PathTraceOptions opt;
  opt.common.spp = 64;
  opt.common.seed = 4;
  test::requireImageMean(renderPathTraced(scene, vis, opt).image, Rgb(0.5f, 1.0f, 2.0f));
}

TEST_CASE("A glTF base colour texture, from a data URI or a buffer view, is read as its sRGB codes", "[gltf][loader]") {
  const test::TempDir dir;
  const auto& codes = kTexelCodes;
  const std::vector<unsigned char> png = texelCodesPng();
  json viaUri = quadFile({{{"mesh", 0}}}, {0});
  viaUri["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = {{"index", 0}};
  viaUri["textures"] = {{{"source", 0}, {"sampler", 0}}};
  viaUri["samplers"] = {{{"wrapS", 33071}, {"wrapT", 10497}}};
  json viaView = viaUri;
  viaUri["images"] = {{{"uri", "data:image/png;base64," + base64(png)}}};
  viaView["buffers"].push_back({{"byteLength", png.size()}, {"uri", "data:application/octet-stream;base64," + base64(png)}});
  viaView["bufferViews"].push_back({{"buffer", 1}, {"byteOffset", 0}, {"byteLength", png.size()}});
  viaView["images"] = {{{"bufferView", 3}, {"mimeType", "image/png"}}};
  for (const json& f : {viaUri, viaView}) {
    const Scene scene = loadWrapped(dir.path, f);
    REQUIRE(scene.textures.size() == 1);
    CHECK(scene.materials[0].kdTexture == 0);
    CHECK(scene.materials[0].kd.r == Approx(0.5));  // the factor, which multiplies the texture
    REQUIRE(scene.textures[0].width == 2);
    REQUIRE(scene.textures[0].height == 1);
    for (int x = 0; x < 2; ++x) {
      const uint32_t texel = scene.texels[scene.textures[0].offset + uint32_t(x)];
      for (int c = 0; c < 3; ++c) CHECK(((texel >> (8 * c)) & 0xff) == codes[x][c]);
    }
    // The sampler's wrapping is the texture's: clamped along u, repeated along v.
    CHECK(scene.textures[0].wrapU == TextureWrap::Clamp);
    CHECK(scene.textures[0].wrapV == TextureWrap::Repeat);
    CHECK(scene.textures[0].nearest == 0);
    CHECK(scene.ignored.empty());
  }
  // KHR_texture_transform: T R S of glTF's coordinates, worked out by hand for the corner whose
  // coordinates are (1, 0): scaled to (2, 0), turned by 90 degrees to (0, -2), moved to (0.25, -1.5);
  // Lucent's v runs up: (0.25, 2.5). The corner (0, 1): (0, 3), (3, 0), (3.25, 0.5): (3.25, 0.5).
  viaUri["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"] = {
      {"KHR_texture_transform", {{"offset", {0.25, 0.5}}, {"rotation", 1.5707963267948966}, {"scale", {2, 3}}}}};
  const Scene moved = loadWrapped(dir.path, viaUri);
  // Texture `texture`'s coordinates at the corner p (its set's, transformed at the lookup).
  const auto uvAt = [](const Scene& s, int32_t texture, Vec3 p) {
    for (uint32_t t = 0; t < s.triangleCount(); ++t)
      for (int k = 0; k < 3; ++k)
        if (s.vertex(t, k) == p) {
          SurfacePoint sp;
          sp.triangle = t, sp.b1 = k == 1 ? 1.0f : 0.0f, sp.b2 = k == 2 ? 1.0f : 0.0f;
          return textureUv(s, s.textures[size_t(texture)], sp);
        }
    FAIL("no vertex at the corner");
    return Vec2{};
  };
  CHECK(uvAt(moved, 0, {1, 0, 0}).x == Approx(0.25).margin(1e-6));
  CHECK(uvAt(moved, 0, {1, 0, 0}).y == Approx(2.5).margin(1e-6));
  CHECK(uvAt(moved, 0, {0, 1, 0}).x == Approx(3.25).margin(1e-6));
  CHECK(uvAt(moved, 0, {0, 1, 0}).y == Approx(0.5).margin(1e-6));
  // The set the texture names: TEXCOORD_1 alone, then set 2, which no texture may read here.
  json second = viaUri;
  auto& attributes = second["meshes"][0]["primitives"][0]["attributes"];
  attributes["TEXCOORD_1"] = attributes["TEXCOORD_0"];
  attributes.erase("TEXCOORD_0");
  second["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["texCoord"] = 1;
  const Scene secondSet = loadWrapped(dir.path, second);
  REQUIRE(secondSet.texcoords1.size() == secondSet.positions.size());
  CHECK(uvAt(secondSet, 0, {1, 0, 0}).y == Approx(2.5).margin(1e-6));
  // A material's textures read their own sets and transforms: the base colour TEXCOORD_0 as it
  // is, the metallic-roughness texture TEXCOORD_1 (here the quad's coordinates mirrored in u) moved
  // by (0.5, 0): at the corner (1, 0), whose coordinates are (1, 0) and (0, 0), the first reads
  // (1, 1) and the second (0.5, 1) in Lucent's coordinates.
  json mixed = quadFile({{{"mesh", 0}}}, {0});
  std::vector<unsigned char> mirrored;
  for (const auto& uv : std::vector<std::array<unsigned char, 2>>{{255, 0}, {0, 0}, {255, 255}, {0, 255}})
    mirrored.insert(mirrored.end(), uv.begin(), uv.end());
  mixed["buffers"].push_back({{"byteLength", mirrored.size()}, {"uri", "data:application/octet-stream;base64," + base64(mirrored)}});
  mixed["bufferViews"].push_back({{"buffer", 1}, {"byteOffset", 0}, {"byteLength", mirrored.size()}});
  mixed["accessors"].push_back({{"bufferView", 3}, {"componentType", 5121}, {"normalized", true}, {"count", 4}, {"type", "VEC2"}});
  mixed["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_1"] = 4;
  mixed["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = {{"index", 0}};
  mixed["materials"][0]["pbrMetallicRoughness"]["metallicRoughnessTexture"] = {
      {"index", 0}, {"texCoord", 1}, {"extensions", {{"KHR_texture_transform", {{"offset", {0.5, 0}}}}}}};
  mixed["textures"] = viaUri["textures"];
  mixed["samplers"] = viaUri["samplers"];
  mixed["images"] = viaUri["images"];
  const Scene both = loadWrapped(dir.path, mixed);
  const Material& m = both.materials[0];
  REQUIRE(m.metallicRoughnessTexture >= 0);
  CHECK(both.textures[size_t(m.kdTexture)].set == 0);
  CHECK(both.textures[size_t(m.metallicRoughnessTexture)].set == 1);
  CHECK(uvAt(both, m.kdTexture, {1, 0, 0}).x == Approx(1).margin(1e-6));
  CHECK(uvAt(both, m.kdTexture, {1, 0, 0}).y == Approx(1).margin(1e-6));
  CHECK(uvAt(both, m.metallicRoughnessTexture, {1, 0, 0}).x == Approx(0.5).margin(1e-6));
  CHECK(uvAt(both, m.metallicRoughnessTexture, {1, 0, 0}).y == Approx(1).margin(1e-6));
  // An OBJ mesh beside the file, read after it or before: its vertices have set 1 coordinates of
  // zero, and the glTF vertices keep theirs.
  {
    std::ofstream(dir.path / "triangle.obj") << "v 5 0 0\nv 6 0 0\nv 5 1 0\nf 1 2 3\n";
    const std::string model = writeFile(dir.path, "mixed.gltf", mixed);
    const json camera = {{"eye", {0, 0, 10}}, {"look_at", {0, 0, 0}}, {"up", {0, 1, 0}}, {"fov_y", 40}, {"resolution", {8, 8}}};
    for (const bool objFirst : {false, true}) {
      json meshes = {{{"gltf", model}}};
      meshes.insert(objFirst ? meshes.begin() : meshes.end(), json{{"obj", (dir.path / "triangle.obj").string()}});
      const Scene withObj = loadScene(writeFile(dir.path, "with-obj.json", {{"camera", camera}, {"meshes", meshes}}), LoadOptions(true));
      INFO("OBJ first: " << objFirst);
      REQUIRE(withObj.texcoords1.size() == withObj.positions.size());
      const int32_t mr = withObj.materials[objFirst ? 1 : 0].metallicRoughnessTexture;
      REQUIRE(mr >= 0);
      CHECK(uvAt(withObj, mr, {1, 0, 0}).x == Approx(0.5).margin(1e-6));
      CHECK(uvAt(withObj, mr, {1, 0, 0}).y == Approx(1).margin(1e-6));
      for (size_t v = 0; v < withObj.positions.size(); ++v)
        if (withObj.positions[v].x >= 5) CHECK((withObj.texcoords1[v].x == 0 && withObj.texcoords1[v].y == 0));
    }
  }
  second["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["texCoord"] = 2;
  REQUIRE_THROWS_WITH(loadWrapped(dir.path, second), Catch::Contains("baseColorTexture.texCoord: TEXCOORD_2 is not read"));
  // A set too large for an integer is quoted as written, not as a cast would print it.
  second["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = {
      {"index", 0}, {"extensions", {{"KHR_texture_transform", {{"texCoord", 1e300}}}}}};
  REQUIRE_THROWS_WITH(loadWrapped(dir.path, second), Catch::Contains("TEXCOORD_1e+300 is not read"));
}

namespace {

uint32_t pngCrc(const unsigned char* data, size_t size) {
  uint32_t crc = 0xffffffffu;
  for (size_t i = 0; i < size; ++i) {
    crc ^= data[i];
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}

// The PNG with its colour-space chunks (sRGB, gAMA, iCCP, cHRM) and its text (where OpenImageIO
// keeps its own colour space) replaced by one gAMA chunk of `gamma` x 100000 (45455: the file says
// its codes are a 1/2.2 power; 100000: linear).
std::vector<unsigned char> withGamma(const std::vector<unsigned char>& png, uint32_t gamma) {
  std::vector<unsigned char> out(png.begin(), png.begin() + 8);
  const auto be32 = [](const unsigned char* p) { return uint32_t(p[0]) << 24 | uint32_t(p[1]) << 16 | uint32_t(p[2]) << 8 | p[3]; };
  const auto put32 = [&](uint32_t v) { for (int k = 3; k >= 0; --k) out.push_back((unsigned char)(v >> (8 * k))); };
  for (size_t at = 8; at + 12 <= png.size();) {
    const uint32_t length = be32(&png[at]);
    const std::string type(reinterpret_cast<const char*>(&png[at + 4]), 4);
    if (type != "sRGB" && type != "gAMA" && type != "iCCP" && type != "cHRM" && type != "tEXt" && type != "iTXt" &&
        type != "zTXt")
      out.insert(out.end(), png.begin() + ptrdiff_t(at), png.begin() + ptrdiff_t(at + 12 + length));
    if (type == "IHDR") {
      const size_t start = out.size();
      put32(4);
      for (const char c : std::string("gAMA")) out.push_back((unsigned char)c);
      put32(gamma);
      put32(pngCrc(&out[start + 4], 8));
    }
    at += 12 + length;
  }
  return out;
}

}  // namespace

TEST_CASE("glTF colour textures are sRGB whatever a PNG's gAMA chunk says", "[gltf][loader]") {
  const test::TempDir dir;
  const auto& codes = kTexelCodes;
  for (const uint32_t gamma : {45455u, 100000u}) {
    INFO("gAMA " << gamma);
    const std::vector<unsigned char> png = withGamma(texelCodesPng(), gamma);
    // The file now says so: read as its metadata says, it would not be sRGB.
    ImageMetadata metadata;
    readImageFromMemory("gamma.png", ".png", png, &metadata);
    CHECK(!isSrgbEncoded("gamma.png", metadata));
    json f = quadFile({{{"mesh", 0}}}, {0});
    f["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = {{"index", 0}};
    f["materials"][0]["emissiveTexture"] = {{"index", 0}};
    f["materials"][0]["emissiveFactor"] = {1, 1, 1};
    f["textures"] = {{{"source", 0}}};
    f["images"] = {{{"uri", "data:image/png;base64," + base64(png)}}};
    const Scene scene = loadWrapped(dir.path, f);
    const Material& m = scene.materials[0];
    for (const int32_t texture : {m.kdTexture, m.emissiveTexture}) {
      REQUIRE(texture >= 0);
      for (int x = 0; x < 2; ++x) {
        const uint32_t texel = scene.texels[scene.textures[size_t(texture)].offset + uint32_t(x)];
        for (int c = 0; c < 3; ++c) CHECK(((texel >> (8 * c)) & 0xff) == codes[x][c]);
      }
    }
  }
}

TEST_CASE("glTF normal and metallic-roughness textures are read as linear data, the normal tilts in the tangent frame",
          "[gltf][loader]") {
  const test::TempDir dir;
  // 1 x 1 PNGs of known codes (Lucent's encoder writes the sRGB code of each linear value).
  const auto png = [](std::array<int, 3> codes) {
    Image image(1, 1, {"R", "G", "B"});
    for (int c = 0; c < 3; ++c) image.at(0, 0, c) = kSrgb8ToLinear[size_t(codes[size_t(c)])];
    return "data:image/png;base64," + base64(encodePng(image));
  };
  json f = quadFile({{{"mesh", 0}}}, {0});
  auto& material = f["materials"][0];
  material["pbrMetallicRoughness"]["metallicFactor"] = 0.8;
  material["pbrMetallicRoughness"]["roughnessFactor"] = 0.9;
  material["pbrMetallicRoughness"]["metallicRoughnessTexture"] = {{"index", 0}};
  material["normalTexture"] = {{"index", 1}, {"scale", 2}};
  f["textures"] = {{{"source", 0}}, {{"source", 1}}};
  // Metallic 64/255 (B), roughness 128/255 (G); a normal of x 2 * 191/255 - 1, y 2 * 128/255 - 1,
  // z 2 * 221/255 - 1 in tangent space.
  f["images"] = {{{"uri", png({0, 128, 64})}}, {{"uri", png({191, 128, 221})}}};
  const double x = 2 * 191 / 255.0 - 1, y = 2 * 128 / 255.0 - 1, z = 2 * 221 / 255.0 - 1;
  // The quad lies in z = 0 facing +z; glTF's u runs along +x, its v along +y, so Lucent's v (1 - v)
  // along -y: tangent +x, bitangent -y, sign -1.
  const auto expectNormal = [&](const Scene& scene, double sx, double scale) {
    REQUIRE(scene.tangents.size() == scene.positions.size());
    for (uint32_t t = 0; t < scene.triangleCount(); ++t) {
      const SurfacePoint sp = surfaceAt(scene, t, 1 / 3.0f, 1 / 3.0f);
      const double px = sx * x * scale, py = -y * scale, len = std::sqrt(px * px + py * py + z * z);
      CHECK(sp.shadingNormal.x == Approx(px / len).margin(1e-5));
      CHECK(sp.shadingNormal.y == Approx(py / len).margin(1e-5));
      CHECK(sp.shadingNormal.z == Approx(z / len).margin(1e-5));
    }
  };
  SECTION("tangents from the texture coordinates") {
    const Scene scene = loadWrapped(dir.path, f);
    const Material& m = scene.materials[0];
    REQUIRE(m.metallicRoughnessTexture >= 0);
    REQUIRE(m.normalTexture >= 0);
    SurfacePoint sp = surfaceAt(scene, 0, 0.25f, 0.25f);
    const SurfaceBsdf b = bsdfAt(scene, sp);
    const double metallic = 0.8 * 64 / 255.0, roughness = 0.9 * 128 / 255.0;
    CHECK(b.gltf.alpha == Approx(roughness * roughness).epsilon(1e-5));
    CHECK(b.gltf.kd.r == Approx(0.5 * (1 - metallic)).epsilon(1e-5));
    CHECK(b.gltf.ks.r == Approx(0.5 * metallic).epsilon(1e-5));  // the quad's specularFactor 0: no dielectric F0
    expectNormal(scene, 1, 2);
    // The default scale, 1.
    f["materials"][0]["normalTexture"].erase("scale");
    expectNormal(loadWrapped(dir.path, f), 1, 1);
    // Mirrored by its node (x to -x): the tilt mirrors with the surface.
    f["nodes"][0]["scale"] = {-1, 1, 1};
    expectNormal(loadWrapped(dir.path, f), -1, 1);
  }
  SECTION("tangents as the file gives them") {
    std::vector<unsigned char> tangents;
    for (int v = 0; v < 4; ++v)
      for (const float c : {1.0f, 0.0f, 0.0f, -1.0f}) append(tangents, c);
    f["buffers"].push_back({{"byteLength", tangents.size()}, {"uri", "data:application/octet-stream;base64," + base64(tangents)}});
    f["bufferViews"].push_back({{"buffer", 1}, {"byteOffset", 0}, {"byteLength", tangents.size()}});
    f["accessors"].push_back({{"bufferView", 3}, {"componentType", 5126}, {"count", 4}, {"type", "VEC4"}});
    f["meshes"][0]["primitives"][0]["attributes"]["TANGENT"] = 4;
    expectNormal(loadWrapped(dir.path, f), 1, 2);
    // The opposite sign turns the bitangent: y's sign flips.
    std::vector<unsigned char> flipped;
    for (int v = 0; v < 4; ++v)
      for (const float c : {1.0f, 0.0f, 0.0f, 1.0f}) append(flipped, c);
    f["buffers"][1]["uri"] = "data:application/octet-stream;base64," + base64(flipped);
    const Scene scene = loadWrapped(dir.path, f);
    const SurfacePoint sp = surfaceAt(scene, 0, 1 / 3.0f, 1 / 3.0f);
    CHECK(sp.shadingNormal.y > 0);
    // Without NORMAL the file's tangents are ignored (the specification: flat normals, tangents
    // made from them): the sign comes from the texture coordinates about the faces' normal again.
    f["meshes"][0]["primitives"][0]["attributes"].erase("NORMAL");
    expectNormal(loadWrapped(dir.path, f), 1, 2);
  }
  SECTION("tangents from the texture coordinates about the faces' normal, without NORMAL") {
    f["meshes"][0]["primitives"][0]["attributes"].erase("NORMAL");
    expectNormal(loadWrapped(dir.path, f), 1, 2);
    // Mirrored by its node, the faces turn over with it: the tilt mirrors with the surface.
    f["nodes"][0]["scale"] = {-1, 1, 1};
    expectNormal(loadWrapped(dir.path, f), -1, 2);
  }
}

TEST_CASE("Tangents on a material without a normal texture are nothing left out", "[gltf][loader]") {
  // They would serve a normal texture only: --strict has nothing to refuse.
  const test::TempDir dir;
  json f = quadFile({{{"mesh", 0}}}, {0});
  std::vector<unsigned char> tangents;
  for (int v = 0; v < 4; ++v)
    for (const float c : {1.0f, 0.0f, 0.0f, 1.0f}) append(tangents, c);
  f["buffers"].push_back({{"byteLength", tangents.size()}, {"uri", "data:application/octet-stream;base64," + base64(tangents)}});
  f["bufferViews"].push_back({{"buffer", 1}, {"byteOffset", 0}, {"byteLength", tangents.size()}});
  f["accessors"].push_back({{"bufferView", 3}, {"componentType", 5126}, {"count", 4}, {"type", "VEC4"}});
  f["meshes"][0]["primitives"][0]["attributes"]["TANGENT"] = 4;
  CHECK(loadWrapped(dir.path, f).ignored.empty());
  // Another attribute still is.
  f["meshes"][0]["primitives"][0]["attributes"]["_TEMPERATURE"] = 4;
  const Scene scene = loadWrapped(dir.path, f);
  REQUIRE(scene.ignored.size() == 1);
  CHECK_THAT(scene.ignored[0], Catch::Contains("attributes._TEMPERATURE (not read)"));
}

TEST_CASE("KHR_materials_specular's textures: its factor times their A (linear), its colour times their RGB (sRGB)",
          "[gltf][loader]") {
  const test::TempDir dir;
  // One 1 x 1 RGBA image of codes (128, 64, 255, 102) for both: the specular factor 0.5 x 102/255,
  // the colour (1, 1, 1) x the sRGB decoding of (128, 64, 255); ior 1.5 (F0 0.04), not metallic.
  json f = quadFile({{{"mesh", 0}}}, {0});
  f["images"] = {{{"uri", "data:image/png;base64," + base64(rgbaPng(1, 1, {128, 64, 255, 102}))}}};
  f["textures"] = {{{"source", 0}}};
  f["materials"][0]["extensions"]["KHR_materials_specular"] = {
      {"specularFactor", 0.5}, {"specularColorFactor", {1, 1, 1}}, {"specularTexture", {{"index", 0}}},
      {"specularColorTexture", {{"index", 0}}}};
  const Scene scene = loadWrapped(dir.path, f);
  const Material& m = scene.materials[0];
  REQUIRE(m.specularTexture >= 0);
  REQUIRE(m.specularColorTexture >= 0);
  SurfacePoint sp = surfaceAt(scene, 0, 0.25f, 0.25f);
  const SurfaceBsdf b = bsdfAt(scene, sp);
  const double specular = 0.5 * 102 / 255.0;
  CHECK(b.gltf.dielectricF90 == Approx(specular).epsilon(1e-5));
  CHECK(b.gltf.f90 == Approx(specular).epsilon(1e-5));
  const int codes[3] = {128, 64, 255};
  for (int c = 0; c < 3; ++c) CHECK(b.gltf.ks[c] == Approx(0.04 * kSrgb8ToLinear[size_t(codes[c])] * specular).epsilon(1e-4));
  // A textureInfo that is not one is refused with its path.
  f["materials"][0]["extensions"]["KHR_materials_specular"]["specularTexture"] = 3;
  REQUIRE_THROWS_WITH(loadWrapped(dir.path, f),
                      Catch::Contains("materials[0].extensions.KHR_materials_specular.specularTexture: expected a textureInfo"));
}

TEST_CASE("KHR_materials_sheen: its colour times the texture's RGB (sRGB), its roughness times the A (linear)",
          "[gltf][loader]") {
  const test::TempDir dir;
  // One 1 x 1 RGBA image of codes (128, 64, 255, 102) for both textures: the sheen colour
  // (1, 0.5, 0.8) x the sRGB decoding of (128, 64, 255), the roughness 0.6 x 102/255. Nothing is
  // left out; with sheen colour black the lobe is the plain metallic-roughness one.
  json f = quadFile({{{"mesh", 0}}}, {0});
  f["extensionsUsed"] = {"KHR_materials_sheen"};
  f["images"] = {{{"uri", "data:image/png;base64," + base64(rgbaPng(1, 1, {128, 64, 255, 102}))}}};
  f["textures"] = {{{"source", 0}}};
  f["materials"][0]["extensions"]["KHR_materials_sheen"] = {
      {"sheenColorFactor", {1, 0.5, 0.8}}, {"sheenRoughnessFactor", 0.6}, {"sheenColorTexture", {{"index", 0}}},
      {"sheenRoughnessTexture", {{"index", 0}}}};
  const Scene scene = loadWrapped(dir.path, f);
  CHECK(scene.ignored.empty());
  const Material& m = scene.materials[0];
  REQUIRE(m.sheenColourTexture >= 0);
  REQUIRE(m.sheenRoughnessTexture >= 0);
  const SurfaceBsdf b = bsdfAt(scene, surfaceAt(scene, 0, 0.25f, 0.25f));
  const int codes[3] = {128, 64, 255};
  const double factor[3] = {1, 0.5, 0.8};
  for (int c = 0; c < 3; ++c)
    CHECK(b.gltf.sheenColour[c] == Approx(factor[c] * kSrgb8ToLinear[size_t(codes[c])]).epsilon(1e-4));
  CHECK(b.gltf.sheenRoughness == Approx(0.6 * 102 / 255.0).epsilon(1e-4));
  // Factors alone; a roughness of 0 is rendered at the smallest one.
  f["materials"][0]["extensions"]["KHR_materials_sheen"] = {{"sheenColorFactor", {0.2, 0.3, 0.4}}};
  const Scene plain = loadWrapped(dir.path, f);
  const SurfaceBsdf p = bsdfAt(plain, surfaceAt(plain, 0, 0.25f, 0.25f));
  CHECK(p.gltf.sheenColour == Rgb(0.2f, 0.3f, 0.4f));
  CHECK(p.gltf.sheenRoughness == kMinSheenRoughness);
  f["materials"][0]["extensions"]["KHR_materials_sheen"] = json::object();
  const Scene none = loadWrapped(dir.path, f);
  CHECK(!bsdfAt(none, surfaceAt(none, 0, 0.25f, 0.25f)).gltf.hasSheen());
  // Out of range, refused with the path.
  f["materials"][0]["extensions"]["KHR_materials_sheen"] = {{"sheenColorFactor", {1.5, 0, 0}}};
  REQUIRE_THROWS_WITH(loadWrapped(dir.path, f),
                      Catch::Contains("materials[0].extensions.KHR_materials_sheen.sheenColorFactor: every value must be in [0, 1]"));
  f["materials"][0]["extensions"]["KHR_materials_sheen"] = {{"sheenRoughnessFactor", -0.1}};
  REQUIRE_THROWS_WITH(loadWrapped(dir.path, f), Catch::Contains("KHR_materials_sheen.sheenRoughnessFactor"));
}

TEST_CASE("KHR_materials_clearcoat: its factors times the textures' R and G (linear), its own normal, emission "
          "beneath it",
          "[gltf][loader]") {
  const test::TempDir dir;
  // Image 0: codes (204, 102, 0) for the coat (R) and its roughness (G); image 1: a tilted normal.
  json f = quadFile({{{"mesh", 0}}}, {0});
  f["extensionsUsed"] = {"KHR_materials_clearcoat"};
  f["images"] = {{{"uri", "data:image/png;base64," + base64(rgbaPng(1, 1, {204, 102, 0, 255}))}},
                 {{"uri", "data:image/png;base64," + base64(rgbaPng(1, 1, {191, 128, 221, 255}))}}};
  f["textures"] = {{{"source", 0}}, {{"source", 1}}};
  auto& material = f["materials"][0];
  material["normalTexture"] = {{"index", 1}};
  material["emissiveFactor"] = {1, 1, 1};
  material["extensions"]["KHR_materials_clearcoat"] = {{"clearcoatFactor", 0.8},
                                                       {"clearcoatTexture", {{"index", 0}}},
                                                       {"clearcoatRoughnessFactor", 0.5},
                                                       {"clearcoatRoughnessTexture", {{"index", 0}}}};
  const Scene scene = loadWrapped(dir.path, f);
  CHECK(scene.ignored.empty());
  const SurfacePoint sp = surfaceAt(scene, 0, 0.25f, 0.25f);
  const SurfaceBsdf b = bsdfAt(scene, sp);
  const double coat = 0.8 * 204 / 255.0, roughness = 0.5 * 102 / 255.0;
  CHECK(b.gltf.coat == Approx(coat).epsilon(1e-5));
  CHECK(b.gltf.coatAlpha == Approx(roughness * roughness).epsilon(1e-5));
  // The base's normal texture tilts its shading normal, not the coat's: that is the quad's normal.
  CHECK(sp.shadingNormal.z < 0.99f);
  CHECK(length(b.gltf.coatNormal - Vec3{0, 0, 1}) < 1e-6f);
  // Emission lies beneath the coat: 1 - coat (0.04 + 0.96 (1 - cos)^5) of it leaves.
  for (const double theta : {0.0, 1.0, 1.4}) {
    const double expected = 1 - coat * (0.04 + 0.96 * std::pow(1 - std::cos(theta), 5));
    const Vec3 towards{float(std::sin(theta)), 0.0f, float(std::cos(theta))};
    const Rgb le = emittedRadiance(scene, 0, 0.25f, 0.25f, towards);
    INFO("theta " << theta);
    CHECK(le.g == Approx(expected).epsilon(1e-5));
  }
  // Its own normal texture, the base's here, tilts it as it tilts the base.
  material["extensions"]["KHR_materials_clearcoat"]["clearcoatNormalTexture"] = {{"index", 1}};
  const Scene mapped = loadWrapped(dir.path, f);
  const SurfacePoint mp = surfaceAt(mapped, 0, 0.25f, 0.25f);
  CHECK(length(bsdfAt(mapped, mp).gltf.coatNormal - mp.shadingNormal) < 1e-6f);
  // Scaled as the base's scale would scale it: twice the tilt.
  material["extensions"]["KHR_materials_clearcoat"]["clearcoatNormalTexture"]["scale"] = 2;
  const Scene scaled = loadWrapped(dir.path, f);
  CHECK(bsdfAt(scaled, surfaceAt(scaled, 0, 0.25f, 0.25f)).gltf.coatNormal.z < mp.shadingNormal.z - 0.05f);
  // Its own normal texture without the base's: tangents are made for it (here from the texture
  // coordinates: tangent +x, bitangent -y), and the base keeps the vertex normal.
  material.erase("normalTexture");
  material["extensions"]["KHR_materials_clearcoat"]["clearcoatNormalTexture"].erase("scale");
  const Scene coatOnly = loadWrapped(dir.path, f);
  REQUIRE(coatOnly.tangents.size() == coatOnly.positions.size());
  const SurfacePoint cp = surfaceAt(coatOnly, 0, 0.25f, 0.25f);
  CHECK(length(cp.shadingNormal - Vec3{0, 0, 1}) < 1e-6f);
  const double x = 2 * 191 / 255.0 - 1, y = 2 * 128 / 255.0 - 1, z = 2 * 221 / 255.0 - 1;
  const double len = std::sqrt(x * x + y * y + z * z);
  const Vec3 coatOnlyNormal = bsdfAt(coatOnly, cp).gltf.coatNormal;
  CHECK(coatOnlyNormal.x == Approx(x / len).margin(1e-5));
  CHECK(coatOnlyNormal.y == Approx(-y / len).margin(1e-5));
  CHECK(coatOnlyNormal.z == Approx(z / len).margin(1e-5));
  // The clear coat's textures may read TEXCOORD_1: the set is read for them.
  f["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_1"] = 2;
  material["extensions"]["KHR_materials_clearcoat"] = {{"clearcoatFactor", 0.8},
                                                       {"clearcoatTexture", {{"index", 0}, {"texCoord", 1}}},
                                                       {"clearcoatRoughnessFactor", 0.5}};
  const Scene set1 = loadWrapped(dir.path, f);
  CHECK(set1.texcoords1.size() == set1.positions.size());
  CHECK(bsdfAt(set1, surfaceAt(set1, 0, 0.25f, 0.25f)).gltf.coat == Approx(coat).epsilon(1e-5));
  f["meshes"][0]["primitives"][0]["attributes"].erase("TEXCOORD_1");
  // A smooth coat is rendered at the smallest roughness and said so; no factor, no coat.
  material["extensions"]["KHR_materials_clearcoat"] = {{"clearcoatFactor", 1}};
  const Scene smooth = loadWrapped(dir.path, f);
  REQUIRE(smooth.ignored.size() == 1);
  CHECK_THAT(smooth.ignored[0], Catch::Contains("clearcoat roughness below 0.0316"));
  CHECK(bsdfAt(smooth, surfaceAt(smooth, 0, 0.25f, 0.25f)).gltf.coatAlpha == kMinGgxAlpha);
  material["extensions"]["KHR_materials_clearcoat"] = json::object();
  const Scene none = loadWrapped(dir.path, f);
  CHECK(none.ignored.empty());
  CHECK(!bsdfAt(none, surfaceAt(none, 0, 0.25f, 0.25f)).gltf.hasCoat());
  CHECK(emittedRadiance(none, 0, 0.25f, 0.25f, {0, 0, 1}) == Rgb(1.0f));
  // Out of range, refused with the path.
  material["extensions"]["KHR_materials_clearcoat"] = {{"clearcoatFactor", 1.5}};
  REQUIRE_THROWS_WITH(loadWrapped(dir.path, f),
                      Catch::Contains("materials[0].extensions.KHR_materials_clearcoat.clearcoatFactor: must be in [0, 1]"));
  material["extensions"]["KHR_materials_clearcoat"] = {{"clearcoatFactor", 1}, {"clearcoatRoughnessFactor", -1}};
  REQUIRE_THROWS_WITH(loadWrapped(dir.path, f), Catch::Contains("KHR_materials_clearcoat.clearcoatRoughnessFactor"));
}

TEST_CASE("A normal texture that tilts most texels past 45 degrees, as a height map does, is warned of", "[gltf][loader]") {
  // Blender's OBJ importer turns map_Bump into a normal texture, and the glTF it exports carries the
  // grey heights as normals (sponza.glb: tilts of about 59 degrees). The render follows the file;
  // the loader says what it sees.
  const test::TempDir dir;
  const auto loadWithTexture = [&](std::array<int, 3> codes) {
    Image image(1, 1, {"R", "G", "B"});
    for (int c = 0; c < 3; ++c) image.at(0, 0, c) = kSrgb8ToLinear[size_t(codes[size_t(c)])];
    json f = quadFile({{{"mesh", 0}}}, {0});
    f["materials"][0]["normalTexture"] = {{"index", 0}};
    f["textures"] = {{{"source", 0}}};
    f["images"] = {{{"uri", "data:image/png;base64," + base64(encodePng(image))}}};
    std::ostringstream warnings;
    std::streambuf* const saved = std::cerr.rdbuf(warnings.rdbuf());
    try {
      loadWrapped(dir.path, f, false);
    } catch (...) {
      std::cerr.rdbuf(saved);
      throw;
    }
    std::cerr.rdbuf(saved);
    return warnings.str();
  };
  // Grey 204: (0.6, 0.6, 0.6), 54.7 degrees from the surface's normal.
  CHECK_THAT(loadWithTexture({204, 204, 204}), Catch::Contains("normal textures of 1 material(s) tilt most of their texels") &&
                                                   Catch::Contains("'grey'") && Catch::Contains("height maps"));
  // (0.5, 0, 0.73): 34 degrees; and a grey below the surface (z < 0).
  CHECK(loadWithTexture({191, 128, 221}).find("normal textures") == std::string::npos);
  CHECK_THAT(loadWithTexture({100, 100, 100}), Catch::Contains("normal textures of 1 material(s)"));
}

TEST_CASE("glTF spot lights: placed by their node, their cone from the extension, and the path tracer's image",
          "[gltf][loader]") {
  const test::TempDir dir;
  // A spot 2 in front of the quad's centre, unrotated: it shines along its node's -z, onto the quad.
  json f = quadFile({{{"mesh", 0}}}, {0});
  f["extensions"]["KHR_lights_punctual"]["lights"] = {
      {{"type", "spot"}, {"intensity", 683 * 4}, {"spot", {{"innerConeAngle", 0.2}, {"outerConeAngle", 0.5}}}}};
  f["nodes"][1] = {{"translation", {0.5, 0.5, 2}}, {"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}};
  const Scene scene = loadWrapped(dir.path, f);
  REQUIRE(scene.lights.size() == 1);
  const Light& l = scene.lights[0];
  CHECK(l.type == LightType::Spot);
  CHECK(near(l.vector, {0.5f, 0.5f, 2}, 1e-6f));
  CHECK(near(l.axis, {0, 0, -1}, 1e-6f));
  CHECK(l.value.g == Approx(4));
  CHECK(l.angleScale == Approx(1 / (std::cos(0.2) - std::cos(0.5))));
  CHECK(l.angleOffset == Approx(-std::cos(0.5) / (std::cos(0.2) - std::cos(0.5))));
  // Refused cones, with their paths.
  for (const auto& [spot, expected] :
       {std::pair{json{{"innerConeAngle", 0.5}, {"outerConeAngle", 0.5}}, "spot.innerConeAngle: must be in [0, outerConeAngle)"},
        std::pair{json{{"outerConeAngle", 2.0}}, "spot.outerConeAngle: must be in (0, pi/2]"}}) {
    json bad = f;
    bad["extensions"]["KHR_lights_punctual"]["lights"][0]["spot"] = spot;
    REQUIRE_THROWS_WITH(loadWrapped(dir.path, bad), Catch::Contains("extensions.KHR_lights_punctual.lights[0]." +
                                                                    std::string(expected)));
  }
}

TEST_CASE("glTF alpha: MASK cuts holes for every query, BLEND lets rays through with probability 1 - alpha",
          "[gltf][loader][visibility]") {
  const test::TempDir dir;
  // A 2 x 1 RGBA PNG base colour texture (codes 188, alpha as stored beside them): its left texel
  // of alpha 51/255 (a hole below the cutoff 0.5), its right opaque.
  const std::vector<unsigned char> png = rgbaPng(2, 1, {188, 188, 188, 51, 188, 188, 188, 255});
  json f = quadFile({{{"mesh", 0}}, {{"mesh", 0}, {"translation", {0, 0, -1}}}}, {0, 1});
  f["images"] = {{{"uri", "data:image/png;base64," + base64(png)}}};
  f["textures"] = {{{"source", 0}}};
  // The first quad masked, the second (1 behind it) opaque: a second material.
  f["materials"].push_back(f["materials"][0]);
  f["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = {{"index", 0}};
  f["materials"][0]["alphaMode"] = "MASK";
  f["meshes"].push_back(f["meshes"][0]);
  f["meshes"][1]["primitives"][0]["material"] = 1;
  f["nodes"][1]["mesh"] = 1;
  const Scene masked = loadWrapped(dir.path, f);
  REQUIRE(masked.materials[0].alphaMode == AlphaMode::Mask);
  CHECK(masked.texels[masked.textures[0].offset] >> 24 == 51);  // the A channel, kept (0.2)
  CHECK(masked.texels[masked.textures[0].offset + 1] >> 24 == 255);
  // Colour as stored beside alpha, not premultiplied by it: both texels alike.
  CHECK((masked.texels[masked.textures[0].offset] & 0xff) == (masked.texels[masked.textures[0].offset + 1] & 0xff));
  CHECK(hasCutOutSurfaces(masked));
  const Visibility vis(masked);
  // Through the left texel's centre the ray passes the hole and meets the opaque quad behind; through
  // the right one it meets the masked quad. Single rays, packets of 8 and 16, and occlusion agree.
  const auto ray = [](float u) { return Ray{{u, 0.5f, 1}, {0, 0, -1}}; };
  const Hit hole = vis.intersect(ray(0.25f)), solid = vis.intersect(ray(0.75f));
  REQUIRE(hole.found());
  REQUIRE(solid.found());
  CHECK(hole.t == Approx(2));
  CHECK(masked.materialIds[hole.triangle] == 1);  // the scene's triangle numbers, whatever the geometry
  CHECK(solid.t == Approx(1));
  CHECK(masked.materialIds[solid.triangle] == 0);
  Ray shortRay = ray(0.25f);
  shortRay.tMax = 1.5f;  // would end before the opaque quad
  CHECK(!vis.occluded(shortRay));
  shortRay.origin.x = 0.75f;
  CHECK(vis.occluded(shortRay));
  Hit hits[16];
  intersectPacket<16>(vis, 16, [&](int i) { return ray(i % 2 ? 0.75f : 0.25f); }, hits);
  for (int i = 0; i < 16; ++i) CHECK(hits[i].t == Approx(i % 2 ? 1 : 2));
  bool blocked[8];
  occludedPacket<8>(vis, 8, [&](int i) { Ray r = ray(i % 2 ? 0.75f : 0.25f); r.tMax = 1.5f; return r; }, blocked);
  for (int i = 0; i < 8; ++i) CHECK(blocked[i] == (i % 2 == 1));

  // BLEND with alpha 0.3 and no texture: about 30% of rays stop at the first quad, each ray's fate
  // the same every time it is traced.
  f["materials"][0]["alphaMode"] = "BLEND";
  f["materials"][0]["pbrMetallicRoughness"].erase("baseColorTexture");
  f["materials"][0]["pbrMetallicRoughness"]["baseColorFactor"] = {0.5, 0.5, 0.5, 0.3};
  const Scene blended = loadWrapped(dir.path, f);
  const Visibility blendVis(blended);
  Rng rng(12);
  const int n = 100000;
  int stopped = 0;
  for (int i = 0; i < n; ++i) {
    const Ray r{{rng.uniform(), rng.uniform(), 1}, {0, 0, -1}};
    const Hit h = blendVis.intersect(r);
    REQUIRE(h.found());
    stopped += h.t < 1.5f;
    if (i < 100) CHECK(blendVis.intersect(r).t == h.t);
  }
  CHECK(std::abs(stopped - 0.3 * n) <= 4.5 * std::sqrt(n * 0.3 * 0.7));
  // A bad mode or cutoff is refused with its path.
  f["materials"][0]["alphaMode"] = "HALF";
  REQUIRE_THROWS_WITH(loadWrapped(dir.path, f), Catch::Contains("materials[0].alphaMode: 'HALF'"));
}

namespace {

// The quad of quadFile with a COLOR_0 accessor (number 4, in a second buffer) of the given component
// type (float, unsigned byte or short) and type (VEC3 or VEC4): per vertex (x, y) (0, 0) red, (1, 0)
// green, (0, 1) blue, (1, 1) grey, alpha 1 where x = 0 and 0 where x = 1. `colours` gets the values
// the file holds, four per vertex (alpha 1 for VEC3).
json quadWithColours(int componentType, int channels, std::vector<float>& colours) {
  json f = quadFile({{{"mesh", 0}}}, {0});
  const double wanted[4][4] = {{1, 0, 0, 1}, {0, 1, 0, 0}, {0, 0, 1, 1}, {0.5, 0.5, 0.5, 0}};
  std::vector<unsigned char> bytes;
  colours.clear();
  const int stride = componentType == 5126 ? 4 * channels : componentType == 5121 ? 4 : 8;  // elements 4-byte aligned
  for (const auto& v : wanted) {
    const size_t start = bytes.size();
    for (int k = 0; k < 4; ++k) {
      const double x = v[k];
      if (k == channels) {
        colours.push_back(1.0f);
        break;
      }
      if (componentType == 5126) append(bytes, float(x)), colours.push_back(float(x));
      if (componentType == 5121) append(bytes, uint8_t(std::lround(x * 255))), colours.push_back(float(std::lround(x * 255) / 255.0));
      if (componentType == 5123)
        append(bytes, uint16_t(std::lround(x * 65535))), colours.push_back(float(std::lround(x * 65535) / 65535.0));
    }
    bytes.resize(start + size_t(stride), 0);
  }
  f["buffers"].push_back({{"byteLength", bytes.size()}, {"uri", "data:application/octet-stream;base64," + base64(bytes)}});
  f["bufferViews"].push_back({{"buffer", 1}, {"byteOffset", 0}, {"byteLength", bytes.size()}, {"byteStride", stride}});
  json accessor = {{"bufferView", 3}, {"componentType", componentType}, {"count", 4}, {"type", channels == 4 ? "VEC4" : "VEC3"}};
  if (componentType != 5126) accessor["normalized"] = true;
  f["accessors"].push_back(accessor);
  f["meshes"][0]["primitives"][0]["attributes"]["COLOR_0"] = 4;
  return f;
}

}  // namespace

TEST_CASE("glTF COLOR_0 multiplies the base colour and alpha: floats, normalized bytes and shorts, RGB and RGBA",
          "[gltf][loader]") {
  const test::TempDir dir;
  std::vector<float> colours;
  for (const auto& [componentType, channels] :
       {std::pair{5126, 3}, std::pair{5126, 4}, std::pair{5121, 4}, std::pair{5123, 3}}) {
    INFO("component type " << componentType << ", " << channels << " channels");
    const Scene scene = loadWrapped(dir.path, quadWithColours(componentType, channels, colours));
    CHECK(scene.ignored.empty());
    REQUIRE(scene.colours.size() == scene.positions.size());
    const Rgb factor = scene.materials[0].kd;
    for (uint32_t t = 0; t < scene.triangleCount(); ++t)
      for (const auto& [b1, b2, corner] : {std::tuple{0.0f, 0.0f, 0}, std::tuple{1.0f, 0.0f, 1}, std::tuple{0.0f, 1.0f, 2}}) {
        const uint32_t v = scene.indices[3 * t + uint32_t(corner)];
        const SurfacePoint sp = surfaceAt(scene, t, b1, b2);
        const float* c = &colours[4 * v];
        CHECK(bsdfAt(scene, sp).diffuse() == Rgb(factor.r * c[0], factor.g * c[1], factor.b * c[2]));
        CHECK(vertexColourAt(scene, sp).alpha == c[3]);
      }
    // Between the vertices, interpolated.
    const SurfacePoint centre = surfaceAt(scene, 0, 1 / 3.0f, 1 / 3.0f);
    const uint32_t* v = &scene.indices[0];
    for (int k = 0; k < 3; ++k)
      CHECK(bsdfAt(scene, centre).diffuse()[k] ==
            Approx(factor[k] * (colours[4 * v[0] + k] + colours[4 * v[1] + k] + colours[4 * v[2] + k]) / 3).epsilon(1e-5));
  }
  // With alphaMode MASK (cutoff 0.5) the alpha cuts a hole where x > 0.5.
  json f = quadWithColours(5121, 4, colours);
  f["materials"][0]["alphaMode"] = "MASK";
  const Scene masked = loadWrapped(dir.path, f);
  const Visibility vis(masked);
  CHECK(vis.intersect(Ray{{0.25f, 0.5f, 1}, {0, 0, -1}}).found());
  CHECK_FALSE(vis.intersect(Ray{{0.75f, 0.5f, 1}, {0, 0, -1}}).found());
  // Integers not normalized, and floats outside [0, 1], are refused.
  f = quadWithColours(5121, 4, colours);
  f["accessors"][4]["normalized"] = false;
  REQUIRE_THROWS_WITH(loadWrapped(dir.path, f), Catch::Contains("accessors[4].normalized: must be true for"));
  f = quadWithColours(5126, 3, colours);
  f["accessors"][4]["componentType"] = 5126;
  std::vector<unsigned char> bright;
  for (int k = 0; k < 12; ++k) append(bright, k == 4 ? 1.5f : 0.5f);
  f["buffers"][1] = {{"byteLength", bright.size()}, {"uri", "data:application/octet-stream;base64," + base64(bright)}};
  REQUIRE_THROWS_WITH(loadWrapped(dir.path, f), Catch::Contains("accessors[4]: element 1 is not a colour in [0, 1]"));
}

TEST_CASE("EXT_mesh_gpu_instancing places a node's mesh once per instance, at the node's transform times the "
          "instance's",
          "[gltf][loader]") {
  const test::TempDir dir;
  // Three instances of the unit quad under a node moved by (0, 0, -1): the first where the node puts
  // it, the second moved by (2, 0, 0), the third turned 90 degrees about z (a quaternion of
  // normalized shorts), scaled by 2 and moved by (0, 3, 0).
  json f = quadFile({{{"mesh", 0}, {"translation", {0, 0, -1}}}}, {0});
  std::vector<unsigned char> bytes;
  for (const float v : {0.0f, 0.0f, 0.0f, 2.0f, 0.0f, 0.0f, 0.0f, 3.0f, 0.0f}) append(bytes, v);
  for (const int16_t v : {0, 0, 0, 32767, 0, 0, 0, 32767, 0, 0, 23170, 23170}) append(bytes, v);
  for (const float v : {1.0f, 1.0f, 1.0f, 1.0f, 1.0f, 1.0f, 2.0f, 2.0f, 2.0f}) append(bytes, v);
  f["buffers"].push_back({{"byteLength", bytes.size()}, {"uri", "data:application/octet-stream;base64," + base64(bytes)}});
  f["bufferViews"].push_back({{"buffer", 1}, {"byteOffset", 0}, {"byteLength", 36}});
  f["bufferViews"].push_back({{"buffer", 1}, {"byteOffset", 36}, {"byteLength", 24}});
  f["bufferViews"].push_back({{"buffer", 1}, {"byteOffset", 60}, {"byteLength", 36}});
  f["accessors"].push_back({{"bufferView", 3}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}});
  f["accessors"].push_back({{"bufferView", 4}, {"componentType", 5122}, {"normalized", true}, {"count", 3}, {"type", "VEC4"}});
  f["accessors"].push_back({{"bufferView", 5}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}});
  f["nodes"][0]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"] = {{"TRANSLATION", 4}, {"ROTATION", 5}, {"SCALE", 6}};
  f["extensionsUsed"].push_back("EXT_mesh_gpu_instancing");
  f["extensionsRequired"] = {"EXT_mesh_gpu_instancing"};
  const Scene scene = loadWrapped(dir.path, f);
  CHECK(scene.ignored.empty());
  REQUIRE(scene.positions.size() == 12);
  REQUIRE(scene.triangleCount() == 6);
  const Vec3 corners[4] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  for (int v = 0; v < 4; ++v) {
    const Vec3 c = corners[v];
    for (const auto& [placed, expected] : {std::pair{scene.positions[size_t(v)], c + Vec3{0, 0, -1}},
                                           std::pair{scene.positions[size_t(4 + v)], c + Vec3{2, 0, -1}},
                                           std::pair{scene.positions[size_t(8 + v)], Vec3{-2 * c.y, 2 * c.x + 3, -1}}})
      for (int k = 0; k < 3; ++k) CHECK(placed[k] == Approx(expected[k]).margin(1e-4));
  }
  // The turned instance's normals turn with it: still +z.
  CHECK(scene.geometricNormal(4).z == Approx(1).margin(1e-5));
  // An attribute of the file's own is left out and said; TRANSLATION alone places copies.
  f["nodes"][0]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"] = {{"TRANSLATION", 4}, {"_ID", 4}};
  const Scene moved = loadWrapped(dir.path, f);
  REQUIRE(moved.ignored.size() == 1);
  CHECK_THAT(moved.ignored[0], Catch::Contains("EXT_mesh_gpu_instancing.attributes._ID (not read)"));
  CHECK(moved.triangleCount() == 6);
  // Refused with their paths: counts that differ, a zero quaternion, no attribute read.
  const auto refusedWith = [&](const json& attributes, const std::string& expected) {
    json g = f;
    g["nodes"][0]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"] = attributes;
    REQUIRE_THROWS_WITH(loadWrapped(dir.path, g), Catch::Contains("nodes[0].extensions.EXT_mesh_gpu_instancing" + expected));
  };
  f["accessors"][6]["count"] = 2;
  refusedWith({{"TRANSLATION", 4}, {"SCALE", 6}}, ".attributes.TRANSLATION: has 3 instances, another attribute 2");
  f["accessors"][6]["count"] = 3;
  refusedWith({{"_ID", 4}}, ".attributes: names no TRANSLATION, ROTATION or SCALE");
  f["buffers"][1]["uri"] = "data:application/octet-stream;base64," + base64(std::vector<unsigned char>(96, 0));
  refusedWith({{"ROTATION", 5}}, ".attributes.ROTATION: instance 0 is a zero quaternion");
}

TEST_CASE("glTF single-sided faces (doubleSided false) are not there from behind for camera rays but there both "
          "ways for every other ray, two-sided ones there for all",
          "[gltf][loader][visibility]") {
  const test::TempDir dir;
  // The quad in z = 0, its counter-clockwise normal +z: a ray from z = 1 meets its front, one from
  // z = -1 its back. Its material says nothing of doubleSided: false, glTF's default.
  json f = quadFile({{{"mesh", 0}}}, {0});
  const auto front = [](float tMax = 1e30f) { return Ray{{0.5f, 0.5f, 1}, {0, 0, -1}, 0, tMax}; };
  const auto back = [](float tMax = 1e30f) { return Ray{{0.5f, 0.5f, -1}, {0, 0, 1}, 0, tMax}; };
  const auto check = [&](const Scene& scene, bool cameraSeesBack) {
    const Visibility vis(scene);
    for (const RayKind kind : {RayKind::Camera, RayKind::Secondary}) {
      const bool seenFromBehind = kind == RayKind::Secondary || cameraSeesBack;
      INFO((kind == RayKind::Camera ? "camera rays" : "secondary rays"));
      const Hit fromFront = vis.intersect(front(), kind), fromBehind = vis.intersect(back(), kind);
      REQUIRE(fromFront.found());
      CHECK(fromFront.t == Approx(1));
      CHECK(fromBehind.found() == seenFromBehind);
      // Packets of 16 and 8, front and back rays in turn, give the single rays' answers.
      Hit hits16[16], hits8[8];
      intersectPacket<16>(vis, 16, [&](int i) { return i % 2 ? back() : front(); }, hits16, kind);
      for (int i = 0; i < 16; ++i) CHECK(hits16[i].found() == (i % 2 == 0 || seenFromBehind));
      intersectPacket<8>(vis, 8, [&](int i) { return i % 2 ? back() : front(); }, hits8, kind);
      for (int i = 0; i < 8; ++i) CHECK(hits8[i].found() == (i % 2 == 0 || seenFromBehind));
    }
    // Occlusion is a secondary query, the same both ways along a segment.
    CHECK(vis.occluded(front(2)));
    CHECK(vis.occluded(back(2)));
    bool blocked[8];
    occludedPacket<8>(vis, 8, [&](int i) { return i % 2 ? back(2) : front(2); }, blocked);
    for (int i = 0; i < 8; ++i) CHECK(blocked[i]);
  };
  const Scene singleSided = loadWrapped(dir.path, f);
  REQUIRE(singleSided.materials[0].culledBehind == 1);
  check(singleSided, false);
  f["materials"][0]["doubleSided"] = true;
  const Scene doubleSided = loadWrapped(dir.path, f);
  REQUIRE(doubleSided.materials[0].culledBehind == 0);
  check(doubleSided, true);
  // A scene file's double_sided true makes a single-sided glTF material two-sided.
  f["materials"][0]["doubleSided"] = false;
  const std::string gltf = writeFile(dir.path, "model.gltf", f);
  const json sceneFile = {{"camera", {{"eye", {0, 0, 10}}, {"look_at", {0, 0, 0}}, {"up", {0, 1, 0}}, {"fov_y", 40},
                                      {"resolution", {8, 8}}}},
                          {"meshes", {{{"gltf", gltf}}}},
                          {"materials", {{"grey", {{"double_sided", true}}}}}};
  const Scene overridden = loadScene(writeFile(dir.path, "two-sided.json", sceneFile), LoadOptions(true));
  REQUIRE(overridden.materials[0].culledBehind == 0);
  check(overridden, true);
}

TEST_CASE("Methods that place points on surfaces refuse scenes with holes, naming the methods that take them",
          "[gltf][cli]") {
  const test::TempDir dir;
  json f = quadFile({{{"mesh", 0}}}, {0});
  f["materials"][0]["alphaMode"] = "MASK";
  f["cameras"] = {{{"type", "perspective"}, {"perspective", {{"yfov", 0.8}, {"aspectRatio", 1.0}, {"znear", 0.1}}}}};
  f["nodes"].push_back({{"camera", 0}, {"translation", {0.5, 0.5, 3}}});
  f["scenes"][0]["nodes"].push_back(int(f["nodes"].size()) - 1);
  const std::string file = writeFile(dir.path, "holes.gltf", f);
  for (const std::string method : {"micro", "particles"}) {
    const test::CliRun r = test::runLucent("render " + file + " --method " + method + " --resolution 8x8 -q -o " +
                                           (dir / "out.exr"));
    INFO(r.output);
    CHECK(r.status == 1);
    CHECK_THAT(r.output, Catch::Contains("--method " + method) && Catch::Contains("alphaMode MASK or BLEND"));
    CHECK(!fs::exists(dir / "out.exr"));
  }
  for (const std::string method : {"pt", "pmfg", "purcell"}) {
    const test::CliRun r = test::runLucent("render " + file + " --method " + method + " --resolution 8x8 --spp 1 -q -o " +
                                           (dir / "out.exr"));
    INFO(r.output);
    CHECK(r.status == 0);
  }
}

TEST_CASE("A glTF file rendered on its own takes the camera named, its node's name or its own", "[gltf][loader]") {
  const test::TempDir dir;
  json f = quadFile({{{"mesh", 0}}}, {0});
  f["cameras"] = {{{"type", "perspective"}, {"name", "wide"}, {"perspective", {{"yfov", 1.0}, {"aspectRatio", 2.0}, {"znear", 0.1}}}},
                  {{"type", "perspective"}, {"name", "narrow"}, {"perspective", {{"yfov", 0.2}, {"znear", 0.1}}}}};
  f["nodes"].push_back({{"camera", 0}, {"name", "front"}, {"translation", {0.5, 0.5, 3}}});
  f["nodes"].push_back({{"camera", 1}, {"name", "side"}, {"translation", {4, 0.5, 0}}});
  f["scenes"][0]["nodes"].push_back(int(f["nodes"].size()) - 2);
  f["scenes"][0]["nodes"].push_back(int(f["nodes"].size()) - 1);
  const std::string file = writeFile(dir.path, "cameras.gltf", f);
  const auto load = [&](const std::string& name) { return loadScene(file, LoadOptions(true, {false, true, 683.0, name})); };
  CHECK(load("").camera.fovY == Approx(1.0 * 180 / kPi));  // the first in node order
  CHECK(load("wide").camera.fovY == Approx(1.0 * 180 / kPi));
  CHECK(load("narrow").camera.fovY == Approx(0.2 * 180 / kPi));
  CHECK(load("side").camera.eye.x == Approx(4));
  CHECK(load("front").camera.width == 512);
  CHECK(load("front").camera.height == 256);
  REQUIRE_THROWS_WITH(load("top"), Catch::Contains("cameras.gltf: cameras: no camera in the scene is named 'top'") &&
                                       Catch::Contains("'front', 'side'"));
}

TEST_CASE("lucent render refuses to write over a glTF file's external buffer or image", "[gltf][cli]") {
  const test::TempDir dir;
  // The quad with its buffer and a base colour PNG as files beside the .gltf.
  json f = quadFile({{{"mesh", 0}}}, {0});
  const std::vector<unsigned char> buffer = quadBuffer();
  std::ofstream(dir / "quad.bin", std::ios::binary).write(reinterpret_cast<const char*>(buffer.data()),
                                                           std::streamsize(buffer.size()));
  f["buffers"][0]["uri"] = "quad.bin";
  Image image(1, 1, {"R", "G", "B"});
  writePng(image, dir / "texture.png");
  f["images"] = {{{"uri", "texture.png"}}};
  f["textures"] = {{{"source", 0}}};
  f["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = {{"index", 0}};
  f["cameras"] = {{{"type", "perspective"}, {"perspective", {{"yfov", 0.8}, {"znear", 0.1}}}}};
  f["nodes"].push_back({{"camera", 0}, {"translation", {0.5, 0.5, 3}}});
  f["scenes"][0]["nodes"].push_back(int(f["nodes"].size()) - 1);
  const std::string file = writeFile(dir.path, "model.gltf", f);
  const auto bytes = [](const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  const std::string pngBefore = bytes(dir / "texture.png");
  const test::CliRun png = test::runLucent("render " + file + " --spp 1 --resolution 8x8 -q -o " + (dir / "out.exr") +
                                           " --png " + (dir / "texture.png"));
  INFO(png.output);
  CHECK(png.status == 1);
  CHECK_THAT(png.output, Catch::Contains("a file this process reads"));
  CHECK(bytes(dir / "texture.png") == pngBefore);
  CHECK(!fs::exists(dir / "out.exr"));
  // The buffer: an output named as it (renamed to .exr to pass the extension check) is refused too.
  fs::rename(dir / "quad.bin", dir / "quad.exr");
  f["buffers"][0]["uri"] = "quad.exr";
  writeFile(dir.path, "model.gltf", f);
  const std::string binBefore = bytes(dir / "quad.exr");
  const test::CliRun exr = test::runLucent("render " + file + " --spp 1 --resolution 8x8 -q -o " + (dir / "quad.exr"));
  INFO(exr.output);
  CHECK(exr.status == 1);
  CHECK_THAT(exr.output, Catch::Contains("a file this process reads"));
  CHECK(bytes(dir / "quad.exr") == binBefore);
}

TEST_CASE("A glTF entry's masking, normal maps and lumens per watt, and the load options', reach its materials and "
          "lights",
          "[gltf][loader]") {
  const test::TempDir dir;
  json f = quadFile({{{"mesh", 0}}}, {0});  // a point light of 683 cd
  Image flat(1, 1, {"R", "G", "B"});
  flat.at(0, 0, 0) = flat.at(0, 0, 1) = kSrgb8ToLinear[128], flat.at(0, 0, 2) = 1.0f;
  f["materials"][0]["normalTexture"] = {{"index", 0}};
  f["textures"] = {{{"source", 0}}};
  f["images"] = {{{"uri", "data:image/png;base64," + base64(encodePng(flat))}}};
  const std::string file = writeFile(dir.path, "model.gltf", f);
  const auto load = [&](const json& entry, const LoadOptions& options) {
    const json scene = {{"camera", {{"eye", {0, 0, 10}}, {"look_at", {0, 0, 0}}, {"up", {0, 1, 0}}, {"fov_y", 40},
                                    {"resolution", {8, 8}}}},
                        {"meshes", {entry}}};
    return loadScene(writeFile(dir.path, "scene.json", scene), options);
  };
  const Scene plain = load({{"gltf", file}}, LoadOptions(true));
  REQUIRE(plain.materials[0].normalTexture >= 0);
  // Height-correlated by default, as Appendix B gives it since its revision of January 2026.
  CHECK(plain.materials[0].masking == GgxMasking::HeightCorrelated);
  CHECK(plain.materials[0].bendsNormalMap == 1);  // bent by default
  CHECK(plain.lights[0].value.g == Approx(1.0f));
  const Scene flagged = load({{"gltf", file}}, LoadOptions(true, {false, false, 341.5, ""}));
  CHECK(flagged.materials[0].masking == GgxMasking::Separable);
  CHECK(flagged.materials[0].bendsNormalMap == 0);
  CHECK(flagged.lights[0].value.g == Approx(2.0f));
  // The entry's own fields win over the load options.
  const Scene own = load({{"gltf", file}, {"masking", "height-correlated"}, {"normal_maps", "bend"},
                          {"lumens_per_watt", 68.3}},
                         LoadOptions(true, {false, false, 341.5, ""}));
  CHECK(own.materials[0].masking == GgxMasking::HeightCorrelated);
  CHECK(own.materials[0].bendsNormalMap == 1);
  CHECK(own.lights[0].value.g == Approx(10.0f));
  CHECK(load({{"gltf", file}, {"normal_maps", "as-given"}}, LoadOptions(true)).materials[0].bendsNormalMap == 0);
  REQUIRE_THROWS_WITH(load({{"gltf", file}, {"masking", "smooth"}}, LoadOptions(true)),
                      Catch::Contains("masking") && Catch::Contains("expected separable or height-correlated"));
  REQUIRE_THROWS_WITH(load({{"gltf", file}, {"normal_maps", "flat"}}, LoadOptions(true)),
                      Catch::Contains("normal_maps") && Catch::Contains("expected bend or as-given"));
}
