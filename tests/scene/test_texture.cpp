// Reflectance texture lookups: sRGB decoding and bilinear filtering with wrap-around.
#include <catch2/catch.hpp>

#include <fstream>

#include "lucent/image/image.h"
#include "lucent/scene/loader.h"
#include "lucent/scene/texture.h"
#include "test_support.h"

using namespace lucent;

namespace {
uint32_t grey(uint8_t v) { return v | v << 8 | v << 16 | 0xffu << 24; }

// A scene of one quad whose material's map_Kd is `file` in `dir`.
Scene texturedQuad(const lucent::test::TempDir& dir, const std::string& file) {
  std::ofstream(dir / "quad.obj") << "mtllib quad.mtl\nusemtl lamp\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";
  std::ofstream(dir / "quad.mtl") << "newmtl lamp\nKd 1 1 1\nKe 1 1 1\nmap_Kd " << file << "\n";
  std::ofstream(dir / "scene.json")
      << R"({"camera": {"eye": [0.5, 0.5, 2], "look_at": [0.5, 0.5, 0], "up": [0, 1, 0], "fov_y": 40,
             "resolution": [4, 4]}, "meshes": [{"obj": "quad.obj"}]})";
  return loadScene(dir / "scene.json", {true});
}
}  // namespace

TEST_CASE("sRGB decoding table matches the transfer function and round-trips", "[texture]") {
  REQUIRE(kSrgb8ToLinear[0] == 0.0f);
  REQUIRE(kSrgb8ToLinear[255] == Approx(1.0f));
  REQUIRE(kSrgb8ToLinear[188] == Approx(0.5029f).epsilon(1e-3));
  for (int i = 0; i < 256; ++i) REQUIRE(std::lround(255 * linearToSrgb(kSrgb8ToLinear[i])) == i);
  const Rgb c = decodeTexel(10 | 128 << 8 | 250 << 16);
  REQUIRE(c.r == kSrgb8ToLinear[10]);
  REQUIRE(c.g == kSrgb8ToLinear[128]);
  REQUIRE(c.b == kSrgb8ToLinear[250]);
}

TEST_CASE("Bilinear lookup interpolates in linear space and wraps around", "[texture]") {
  // 2x2 texture, row 0 at the top (v = 1): top row 0, 255; bottom row 255, 0.
  const std::vector<uint32_t> texels = {grey(0), grey(255), grey(255), grey(0)};
  const Texture t{0, 2, 2};
  // Texel centres return texel values exactly.
  REQUIRE(bilinear(t, texels.data(), {0.25f, 0.75f}).g == Approx(0.0f).margin(1e-6));
  REQUIRE(bilinear(t, texels.data(), {0.75f, 0.75f}).g == Approx(1.0f));
  REQUIRE(bilinear(t, texels.data(), {0.25f, 0.25f}).g == Approx(1.0f));
  // Half-way between two texels: the mean of the linear values, not of the codes.
  REQUIRE(bilinear(t, texels.data(), {0.5f, 0.75f}).g == Approx(0.5f));
  // At u = 0 the lookup blends the last column with the first (wrap-around), as at u = 1 and u = -1.
  REQUIRE(bilinear(t, texels.data(), {0.0f, 0.75f}).g == Approx(0.5f));
  REQUIRE(bilinear(t, texels.data(), {1.0f, 0.75f}).g == Approx(0.5f));
  REQUIRE(bilinear(t, texels.data(), {-0.75f, 0.75f}).g == Approx(0.0f).margin(1e-6));
  REQUIRE(bilinear(t, texels.data(), {2.75f, 1.75f}).g == Approx(1.0f));
  // The centre of the texture: all four texels equally.
  REQUIRE(bilinear(t, texels.data(), {0.5f, 0.5f}).g == Approx(0.5f));
}

TEST_CASE("Textures: 8-bit files are decoded from sRGB, float files read as linear", "[texture]") {
  const lucent::test::TempDir dir("texture");
  Image linearHalf(1, 1, {"R", "G", "B"});
  for (int c = 0; c < 3; ++c) linearHalf.at(0, 0, c) = 0.5f;
  writePng(linearHalf, dir / "half.png");  // stored as sRGB code 188
  writeExr(linearHalf, dir / "half.exr");  // stored as linear 0.5
  for (const char* file : {"half.png", "half.exr"}) {
    const Scene scene = texturedQuad(dir, file);
    REQUIRE(scene.texels.size() == 1);
    INFO(file);
    REQUIRE(decodeTexel(scene.texels[0]).g == Approx(0.5f).epsilon(0.01));
  }
}

TEST_CASE("An 8-bit sRGB texture keeps every code, a float texture is clamped and encoded", "[texture]") {
  // The loader keeps an 8-bit file's codes as they are (what decoding to linear and encoding back
  // would give), and encodes a linear file's values, clamped to reflectance [0, 1], to the nearest
  // code (negative texels are an error). All 256 codes in each channel, in different orders.
  const lucent::test::TempDir dir("texture-codes");
  auto code = [](int x, int c) { return c == 0 ? x : c == 1 ? 255 - x : (37 * x + 11) % 256; };
  Image codes(256, 1, {"R", "G", "B"}), linear(256, 1, {"R", "G", "B"});
  for (int x = 0; x < 256; ++x)
    for (int c = 0; c < 3; ++c) {
      codes.at(x, 0, c) = kSrgb8ToLinear[code(x, c)];  // written back as code(x, c)
      linear.at(x, 0, c) = 1.2f * float(code(x, c)) / 255.0f;  // some above 1
    }
  writePng(codes, dir / "codes.png");
  writeExr(linear, dir / "linear.exr");
  for (const char* file : {"codes.png", "linear.exr"}) {
    const Scene scene = texturedQuad(dir, file);
    REQUIRE(scene.texels.size() == 256);
    for (int x = 0; x < 256; ++x) {
      INFO(file << ", texel " << x);
      const uint32_t texel = scene.texels[size_t(x)];
      CHECK(texel >> 24 == 255);
      for (int c = 0; c < 3; ++c) {
        const uint32_t byte = (texel >> (8 * c)) & 0xff;
        if (file[0] == 'c') {
          CHECK(byte == uint32_t(code(x, c)));
        } else {
          const float v = std::clamp(linear.at(x, 0, c), 0.0f, 1.0f);
          CHECK(byte == uint32_t(std::lround(255.0f * linearToSrgb(v))));
        }
      }
    }
  }
}

TEST_CASE("Texture wrapping and filtering: glTF's repeat, clamp and mirror, bilinear and nearest", "[texture]") {
  // A 2 x 1 texture of linear codes 0 and 255 in R; u in texture units, v at the row's centre.
  const std::vector<uint32_t> texels = {0xff000000u, 0xff0000ffu};
  Texture t;
  t.width = 2;
  t.height = 1;
  const auto at = [&](float u) { return bilinear(bilinearFootprint(t, texels.data(), {u, 0.5f}), kUnorm8ToFloat).r; };
  SECTION("repeat: between the last texel and the first across the edge, the default path") {
    CHECK(at(0.25f) == Approx(0.0f).margin(1e-6));
    CHECK(at(0.75f) == Approx(1.0f));
    CHECK(at(1.0f) == Approx(0.5f));
    CHECK(at(-0.25f) == Approx(1.0f));
    t.wrapV = TextureWrap::Clamp;  // the non-default path, repeating along u: the same values
    CHECK(at(0.0f) == Approx(0.5f));
    CHECK(at(-0.25f) == Approx(1.0f));
  }
  SECTION("clamp: the edge texels extend outwards") {
    t.wrapU = TextureWrap::Clamp;
    CHECK(at(0.0f) == Approx(0.0f).margin(1e-6));
    CHECK(at(-3.0f) == Approx(0.0f).margin(1e-6));
    CHECK(at(1.0f) == Approx(1.0f));
    CHECK(at(7.5f) == Approx(1.0f));
    CHECK(at(0.5f) == Approx(0.5f));
  }
  SECTION("mirror: every other period reversed") {
    t.wrapU = TextureWrap::Mirror;
    CHECK(at(1.25f) == Approx(at(0.75f)));
    CHECK(at(1.75f) == Approx(at(0.25f)));
    CHECK(at(-0.25f) == Approx(at(0.25f)));
    CHECK(at(2.25f) == Approx(at(0.25f)));
    CHECK(at(1.0f) == Approx(1.0f));  // the mirror's edge: the last texel on both sides
  }
  SECTION("nearest: the texel holding the point, no blend") {
    t.nearest = 1;
    CHECK(at(0.49f) == Approx(0.0f).margin(1e-6));
    CHECK(at(0.51f) == Approx(1.0f));
    CHECK(at(0.99f) == Approx(1.0f));
    t.wrapU = TextureWrap::Clamp;
    CHECK(at(-0.5f) == Approx(0.0f).margin(1e-6));
    CHECK(at(1.5f) == Approx(1.0f));
  }
}
