#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <random>

#include <half.h>
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>

#include "lucent/core/srgb.h"
#include "lucent/image/comparison.h"
#include "lucent/image/image.h"
#include "lucent/image/metrics.h"
#include "lucent/image/noise_tests.h"
#include "test_support.h"

namespace fs = std::filesystem;
using namespace lucent;

namespace {

uint32_t bits(float f) {
  uint32_t u;
  std::memcpy(&u, &f, 4);
  return u;
}

Image makeImage(int w, int h, std::vector<std::string> channels, std::vector<float> pixels) {
  Image image(w, h, std::move(channels));
  REQUIRE(pixels.size() == image.pixels().size());
  image.pixels() = std::move(pixels);
  return image;
}

using test::quoted;
using test::runLucent;
using test::TempDir;

}  // namespace

TEST_CASE("Image stores interleaved named channels") {
  Image image(3, 2, {"R", "G", "B", "albedo.R"});
  CHECK(image.pixels().size() == 3 * 2 * 4);
  CHECK(image.channelIndex("albedo.R") == 3);
  CHECK(image.channelIndex("A") == -1);
  image.at(2, 1, 3) = 7;
  CHECK(image.pixels()[(1 * 3 + 2) * 4 + 3] == 7);
}

TEST_CASE("EXR round-trip is bit-exact for every channel and keeps the metadata") {
  TempDir dir;
  const std::vector<std::string> channels = {"R", "G", "B", "albedo.R", "albedo.G", "albedo.B",
                                             "depth.Z"};
  Image image(5, 3, channels);
  const float special[] = {0.0f, -0.0f, 1e-40f /* denormal */, -3.5f, 3.4e38f,
                           std::numeric_limits<float>::infinity(), 0.1f};
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> uniform(-10.0f, 10.0f);
  for (size_t i = 0; i < image.pixels().size(); ++i)
    image.pixels()[i] = i < std::size(special) ? special[i] : uniform(rng);
  const ImageMetadata metadata = {{"lucent:method", "pt"}, {"lucent:spp", "1024"},
                                  {"lucent:scene_hash", "9f86d081884c7d65"}};
  const std::string path = dir / "out.exr";
  writeExr(image, path, metadata);
  CHECK(dir.entries().size() == 1);  // no temporary file left behind

  ImageMetadata readBack;
  const Image loaded = readImage(path, &readBack);
  REQUIRE(loaded.width() == 5);
  REQUIRE(loaded.height() == 3);
  REQUIRE(loaded.channelCount() == int(channels.size()));
  // EXR stores channels by name; compare by name rather than by position.
  for (int c = 0; c < image.channelCount(); ++c) {
    const int lc = loaded.channelIndex(channels[c]);
    REQUIRE(lc >= 0);
    for (int y = 0; y < 3; ++y)
      for (int x = 0; x < 5; ++x) REQUIRE(bits(loaded.at(x, y, lc)) == bits(image.at(x, y, c)));
  }
  for (const auto& entry : metadata)
    CHECK(std::find(readBack.begin(), readBack.end(), entry) != readBack.end());
}

TEST_CASE("EXR overwrite replaces the file") {
  TempDir dir;
  const std::string path = dir / "out.exr";
  writeExr(makeImage(1, 1, {"Y"}, {1.0f}), path);
  writeExr(makeImage(1, 1, {"Y"}, {2.0f}), path);
  CHECK(readImage(path).at(0, 0, 0) == 2.0f);
  CHECK(dir.entries().size() == 1);
}

TEST_CASE("The same image and metadata give the same EXR bytes, and what the header cannot hold is refused") {
  // No time of writing in the header: a file's bytes are its pixels' and attributes' alone.
  TempDir dir;
  const Image image = makeImage(2, 1, {"R", "G", "B"}, {0.1f, 0.2f, 0.3f, 4.0f, 5.0f, 6.0f});
  const ImageMetadata metadata = {{"lucent:method", "pt"}};
  writeExr(image, dir / "a.exr", metadata);
  writeExr(image, dir / "b.exr", metadata);
  auto bytes = [](const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  CHECK(bytes(dir / "a.exr") == bytes(dir / "b.exr"));
  // Two channels of one name, or an attribute named as one of the header's own, are refused, and
  // nothing is left behind.
  CHECK_THROWS_WITH(writeExr(makeImage(1, 1, {"R", "R"}, {1, 2}), dir / "twice.exr"),
                    Catch::Contains("twice.exr") && Catch::Contains("two channels have the same name"));
  CHECK_THROWS_WITH(writeExr(image, dir / "own.exr", {{"compression", "none"}}),
                    Catch::Contains("own.exr") && Catch::Contains("'compression' is one of the EXR header's own"));
  CHECK(dir.entries().size() == 2);
}

TEST_CASE("PNG is sRGB-encoded, clamped and rounded") {
  TempDir dir;
  // Per pixel: grey 0, 0.5, 1, 2, then one with different R, G, B, and negative and NaN values.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  Image image = makeImage(6, 1, {"R", "G", "B", "A"},
                          {0, 0, 0, 1, 0.5f, 0.5f, 0.5f, 1, 1, 1, 1, 1, 2, 2, 2, 1,
                           0.0031308f, 0.2f, 0.8f, 1, -1, nan, 0.001f, 1});
  const std::string path = dir / "out.png";
  writePng(image, path);
  const Image loaded = readImage(path);
  REQUIRE(loaded.channels() == std::vector<std::string>{"R", "G", "B"});
  auto byte = [&](int x, int c) { return std::lround(loaded.at(x, 0, c) * 255.0f); };
  const long expected[6][3] = {{0, 0, 0}, {188, 188, 188}, {255, 255, 255}, {255, 255, 255},
                               {10, 124, 231}, {0, 0, 3}};
  for (int x = 0; x < 6; ++x)
    for (int c = 0; c < 3; ++c) {
      INFO("pixel " << x << " channel " << c);
      CHECK(byte(x, c) == expected[x][c]);
    }
  CHECK(dir.entries().size() == 1);
}

TEST_CASE("PNG needs R, G and B") {
  TempDir dir;
  CHECK_THROWS_AS(writePng(makeImage(1, 1, {"R", "G"}, {0, 0}), dir / "x.png"), std::runtime_error);
  CHECK(dir.entries().size() == 0);
}

TEST_CASE("Writing into a missing directory throws naming the path and leaves no file") {
  TempDir dir;
  const Image image = makeImage(1, 1, {"R", "G", "B"}, {1, 2, 3});
  for (const std::string name : {"missing/out.exr", "missing/out.png"}) {
    const std::string path = dir / name;
    try {
      name.ends_with(".exr") ? writeExr(image, path) : writePng(image, path);
      FAIL("no exception for " << path);
    } catch (const std::runtime_error& e) {
      CHECK_THAT(e.what(), Catch::Contains(path));
    }
  }
  CHECK(dir.entries().size() == 0);
}

TEST_CASE("A failed rename removes the temporary file") {
  TempDir dir;
  // The target is a non-empty directory: the temporary file is written, the rename fails.
  fs::create_directories(dir.path / "out.exr" / "keep");
  CHECK_THROWS_WITH(writeExr(makeImage(1, 1, {"Y"}, {1}), dir / "out.exr"),
                    Catch::Contains(dir / "out.exr"));
  CHECK(dir.entries().size() == 1);
  CHECK(fs::is_directory(dir.path / "out.exr"));
}

TEST_CASE("Reading a missing or broken file names it") {
  TempDir dir;
  CHECK_THROWS_WITH(readImage(dir / "none.exr"), Catch::Contains(dir / "none.exr"));
  std::ofstream(dir / "broken.exr") << "not an image";
  CHECK_THROWS_WITH(readImage(dir / "broken.exr"), Catch::Contains(dir / "broken.exr"));
}

TEST_CASE("PFM, as GPU programs dump it: colour and grey, both byte orders, rows from the bottom") {
  // Rows are stored bottom to top; a negative scale means little-endian floats.
  const auto pfm = [](bool colour, bool littleEndian, int width, int height, const std::vector<float>& topDown) {
    std::string bytes = std::string(colour ? "PF" : "Pf") + "\n" + std::to_string(width) + " " + std::to_string(height) +
                        "\n" + (littleEndian ? "-1.0" : "1.0") + "\n";
    const int channels = colour ? 3 : 1;
    for (int y = height - 1; y >= 0; --y)
      for (int i = 0; i < width * channels; ++i) {
        uint32_t u = bits(topDown[size_t(y * width * channels + i)]);
        for (int b = 0; b < 4; ++b) bytes += char(littleEndian ? (u >> (8 * b)) & 0xff : (u >> (8 * (3 - b))) & 0xff);
      }
    return bytes;
  };
  TempDir dir;
  const std::vector<float> colour = {1, 10, 100, 2, 20, 200, 3, 30, 300, 4, 40, 400, 5, 50, 500, 6, 60, 600};
  for (const bool little : {true, false}) {
    std::ofstream(dir / "c.pfm", std::ios::binary) << pfm(true, little, 3, 2, colour);
    const Image c = readImage(dir / "c.pfm");
    REQUIRE(c.width() == 3);
    REQUIRE(c.height() == 2);
    REQUIRE(c.channels() == std::vector<std::string>{"R", "G", "B"});
    CHECK(c.pixels() == colour);
    // Grey: the same value in R, G and B.
    std::ofstream(dir / "g.pfm", std::ios::binary) << pfm(false, little, 3, 2, {1, 2, 3, 4, 5, 6.5f});
    const Image g = readImage(dir / "g.pfm");
    REQUIRE(g.channels() == std::vector<std::string>{"R", "G", "B"});
    CHECK(g.at(2, 1, 0) == 6.5f);
    CHECK(g.at(2, 1, 2) == 6.5f);
    CHECK(g.at(0, 0, 1) == 1.0f);
  }
  // Cut short, and a header claiming far more than the file holds: refused, naming the file.
  const std::string whole = pfm(true, true, 3, 2, colour);
  std::ofstream(dir / "cut.pfm", std::ios::binary) << whole.substr(0, whole.size() - 8);
  CHECK_THROWS_WITH(readImage(dir / "cut.pfm"), Catch::Contains("cut.pfm"));
  std::ofstream(dir / "huge.pfm", std::ios::binary) << "PF\n4000 4000\n-1.0\n" << whole.substr(whole.find("-1.0\n") + 5);
  CHECK_THROWS_WITH(readImage(dir / "huge.pfm"), Catch::Contains("huge.pfm") && Catch::Contains("more than its"));
}

TEST_CASE("A truncated JPEG is refused, not read with grey where its data stops") {
  // libjpeg fills a cut stream with grey and warns; OpenImageIO drops the warning.
  const fs::path whole = LUCENT_SOURCE_DIR "/scenes/ring/wood-floorboards-texture.jpg";
  std::string bytes;
  {
    std::ifstream in(whole, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  REQUIRE(readImage(whole).width() > 0);
  TempDir dir;
  for (const size_t keep : {bytes.size() / 2, bytes.size() - 2, size_t(3), size_t(600)}) {
    std::ofstream(dir / "cut.jpg", std::ios::binary) << bytes.substr(0, keep);
    CHECK_THROWS_WITH(readImage(dir / "cut.jpg"), Catch::Contains("cut.jpg") && Catch::Contains("truncated"));
    const auto* data = reinterpret_cast<const unsigned char*>(bytes.data());
    CHECK_THROWS_WITH(readImageFromMemory("cut.jpg", ".jpg", {data, keep}), Catch::Contains("truncated"));
  }
  // What follows the end-of-image marker is not the image's (cameras append data there).
  std::ofstream(dir / "tail.jpg", std::ios::binary) << bytes << "trailing bytes";
  CHECK(readImage(dir / "tail.jpg").width() == readImage(whole).width());
}

TEST_CASE("An image header claiming more than 2^26 pixels is refused before its pixels are allocated") {
  // A valid 1 x 1 PNG whose header is then made to claim 20,000 x 20,000: 69 bytes.
  TempDir dir;
  writePng(makeImage(1, 1, {"R", "G", "B"}, {0.5f, 0.5f, 0.5f}), dir / "small.png");
  std::string bytes;
  {
    std::ifstream in(dir / "small.png", std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  REQUIRE(bytes.substr(12, 4) == "IHDR");
  auto putBigEndian = [&](size_t at, uint32_t value) {
    for (int k = 0; k < 4; ++k) bytes[at + size_t(k)] = char((value >> (8 * (3 - k))) & 0xff);
  };
  putBigEndian(16, 20000);  // width
  putBigEndian(20, 20000);  // height
  // The chunk's CRC-32 over its type and data (PNG specification, annex D).
  uint32_t crc = 0xffffffffu;
  for (size_t i = 12; i < 12 + 4 + 13; ++i) {
    crc ^= uint8_t(bytes[i]);
    for (int b = 0; b < 8; ++b) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
  }
  putBigEndian(12 + 4 + 13, crc ^ 0xffffffffu);
  std::ofstream(dir / "huge.png", std::ios::binary) << bytes;
  CHECK_THROWS_WITH(readImage(dir / "huge.png"), Catch::Contains("huge.png") && Catch::Contains("20000 x 20000"));
}

TEST_CASE("Metrics match hand-computed values on a 2x1 image") {
  // Pixels (R,G): image (1,0) (3,0.5); reference (1,0) (2,1).
  const Image image = makeImage(2, 1, {"R", "G"}, {1, 0, 3, 0.5f});
  const Image reference = makeImage(2, 1, {"R", "G"}, {1, 0, 2, 1});
  // The reference's channels in another order must give the same result.
  const Image swapped = makeImage(2, 1, {"G", "R"}, {0, 1, 1, 2});
  for (const Image* ref : {&reference, &swapped}) {
    const ImageError e = compareImages(image, *ref);
    REQUIRE(e.perChannel.size() == 2);
    const ChannelError& r = e.perChannel[0];
    const ChannelError& g = e.perChannel[1];
    CHECK(r.channel == "R");
    CHECK(g.channel == "G");
    CHECK(r.rmse == Approx(std::sqrt(0.5)));
    CHECK(r.mae == Approx(0.5));
    CHECK(r.relmse == Approx(0.5 / (2.01 * 2.01)));
    CHECK(r.smape == Approx(0.5 * 2.0 / 5.0));
    CHECK(g.rmse == Approx(std::sqrt(0.125)));
    CHECK(g.mae == Approx(0.25));
    CHECK(g.relmse == Approx(0.5 * 0.25 / (1.01 * 1.01)));
    CHECK(g.smape == Approx(0.5 * (2 * 0.5 / 1.5)));  // 0 where both are 0
    CHECK(e.overall.rmse == Approx(std::sqrt(1.25 / 4)));
    CHECK(e.overall.mae == Approx(1.5 / 4));
    CHECK(e.overall.relmse == Approx((1 / (2.01 * 2.01) + 0.25 / (1.01 * 1.01)) / 4));
    CHECK(e.overall.smape == Approx((0.4 + 2 * 0.5 / 1.5) / 4));
  }
  const ImageError same = compareImages(image, image);
  CHECK(same.overall.rmse == 0);
  CHECK(same.overall.smape == 0);
}

TEST_CASE("Metrics reject different sizes and channel sets") {
  const Image a = makeImage(2, 1, {"R", "G"}, {0, 0, 0, 0});
  CHECK_THROWS_AS(compareImages(a, Image(1, 2, {"R", "G"})), std::invalid_argument);
  CHECK_THROWS_WITH(compareImages(a, Image(1, 2, {"R", "G"})),
                    Catch::Contains("2x1") && Catch::Contains("1x2"));
  CHECK_THROWS_AS(compareImages(a, Image(2, 1, {"R", "B"})), std::invalid_argument);
  CHECK_THROWS_WITH(compareImages(a, Image(2, 1, {"R", "G", "B"})),
                    Catch::Contains("[R, G]") && Catch::Contains("[R, G, B]"));
  CHECK_THROWS_AS(errorHeatmap(a, Image(3, 1, {"R", "G"}), ErrorMetric::Mae),
                  std::invalid_argument);
}

TEST_CASE("Another renderer's RGBA compares with a reference that has layers, by the channels both have") {
  // Blender writes RGBA; Lucent's references carry layers. Both hold R, G and B: those are compared,
  // and what one image has alone is named, not compared.
  const Image rgba = makeImage(2, 1, {"R", "G", "B", "A"}, {1, 2, 3, 1, 2, 2, 2, 1});
  const Image reference = makeImage(2, 1, {"R", "G", "B", "albedo.R", "variance.R"}, {1, 2, 3, 0.5f, 0, 2, 2, 4, 0.5f, 0});
  const ImageError e = compareImages(rgba, reference);
  REQUIRE(e.perChannel.size() == 3);
  CHECK(e.notCompared.image == std::vector<std::string>{"A"});
  CHECK(e.notCompared.reference == std::vector<std::string>{"albedo.R"});
  CHECK(e.perChannel[2].channel == "B");
  CHECK(e.perChannel[2].mae == Approx(1.0));  // |3 - 3| and |2 - 4| over two pixels
  CHECK(e.overall.mae == Approx(2.0 / 6));
  CHECK_NOTHROW(checkComparable({2, 1, rgba.channels(), {}}, {2, 1, reference.channels(), {}}, false));
  // Without R, G and B in both, differing channels are still refused.
  CHECK_THROWS_WITH(compareImages(makeImage(2, 1, {"R", "G", "A"}, {0, 0, 0, 0, 0, 0}), reference),
                    Catch::Contains("need"));
}

TEST_CASE("An 8-bit image against a reference brighter than 1 is refused, or compared clipped with --ldr") {
  // The reference's lamp is 2.5: an 8-bit image stops at 1, and the difference would read as a bias.
  const Image reference = makeImage(2, 1, {"R", "G", "B"}, {2.5f, 0.5f, 0.25f, 0.5f, 0.5f, 0.5f});
  const Image display = makeImage(2, 1, {"R", "G", "B"}, {1.0f, 0.5f, 0.25f, 0.5f, 0.5f, 0.5f});
  CHECK_THROWS_WITH(compareImagePair(display, reference, {}, true, false),
                    Catch::Contains("8-bit") && Catch::Contains("exceeds 1 in 1 values") && Catch::Contains("--ldr"));
  ComparisonSettings ldr;
  ldr.ldr = true;
  ldr.maxError = 0.0;
  const ImageComparison c = compareImagePair(display, reference, ldr, true, false);
  CHECK(c.verdict == Verdict::Pass);
  CHECK(nlohmann::json::parse(c.json)["ldr"]["reference_values_clipped"] == 1);
  // An HDR candidate, or an 8-bit reference, is compared as it is.
  CHECK(compareImagePair(display, reference, ldr, false, false).verdict == Verdict::Fail);
  CHECK_NOTHROW(compareImagePair(display, reference, {}, true, true));
}

TEST_CASE("Metrics leave out a reference's variance channels, so any render compares with a reference") {
  const Image image = makeImage(2, 1, {"R", "G", "B"}, {1, 1, 1, 2, 2, 2});
  const Image reference = makeImage(2, 1, {"R", "G", "B", "variance.R", "variance.G", "variance.B"},
                                    {1, 1, 1, 9, 9, 9, 1, 1, 1, 9, 9, 9});
  const ImageError e = compareImages(image, reference);
  CHECK(e.perChannel.size() == 3);
  CHECK(e.overall.mae == Approx(0.5));  // the variances (9) are not compared with anything
  const ImageError back = compareImages(reference, image);
  CHECK(back.perChannel.size() == 3);
  CHECK(back.overall.mae == Approx(0.5));
  const Image heat = errorHeatmap(image, reference, ErrorMetric::Mae);
  CHECK(heat.width() == 2);
  // Channels other than the variances must still match.
  CHECK_THROWS_AS(compareImages(makeImage(2, 1, {"R", "G"}, {0, 0, 0, 0}), reference), std::invalid_argument);
}

TEST_CASE("Metric names parse") {
  for (const char* name : {"rmse", "mae", "relmse", "smape"})
    CHECK(std::string(errorMetricName(parseErrorMetric(name))) == name);
  CHECK_THROWS_AS(parseErrorMetric("psnr"), std::invalid_argument);
}

TEST_CASE("Error heatmap is monotonic in the error and clamps at the maximum") {
  // Absolute errors 0, 1, 2, 4 (mean over one channel).
  const Image reference = makeImage(4, 1, {"Y"}, {0, 0, 0, 0});
  const Image image = makeImage(4, 1, {"Y"}, {0, 1, 2, 4});
  const Image heat = errorHeatmap(image, reference, ErrorMetric::Mae, 2.0);
  REQUIRE(heat.channels() == std::vector<std::string>{"R", "G", "B"});
  REQUIRE(heat.width() == 4);
  auto luminance = [&](int x) {
    return 0.2126f * heat.at(x, 0, 0) + 0.7152f * heat.at(x, 0, 1) + 0.0722f * heat.at(x, 0, 2);
  };
  CHECK(luminance(0) < luminance(1));
  CHECK(luminance(1) < luminance(2));
  for (int c = 0; c < 3; ++c) CHECK(heat.at(3, 0, c) == heat.at(2, 0, c));
  // Without a maximum the 99th percentile sets the scale: errors 0..100 saturate at 99.
  Image ramp(101, 1, {"Y"});
  for (int x = 0; x <= 100; ++x) ramp.at(x, 0, 0) = float(x);
  const Image autoHeat = errorHeatmap(ramp, Image(101, 1, {"Y"}), ErrorMetric::Mae);
  CHECK(autoHeat.at(98, 0, 1) < autoHeat.at(99, 0, 1));
  CHECK(autoHeat.at(99, 0, 1) == autoHeat.at(100, 0, 1));
}

TEST_CASE("lucent compare reports metrics and exits by threshold") {
  TempDir dir;
  const Image reference = makeImage(2, 1, {"R", "G", "B"}, {1, 1, 1, 1, 1, 1});
  const Image image = makeImage(2, 1, {"R", "G", "B"}, {1, 1, 1, 1.1f, 1, 1});
  writeExr(reference, dir / "ref.exr");
  writeExr(image, dir / "img.exr");
  const std::string files = quoted(dir / "img.exr") + " " + quoted(dir / "ref.exr");
  const double relmse = 0.01 / (1.01 * 1.01) / 6;  // one sample off by 0.1

  SECTION("under the threshold, with a heatmap") {
    const test::CliRun r = runLucent("compare " + files + " --max-error 0.01 --heatmap " +
                                  quoted(dir / "heat.png"));
    CHECK(r.status == 0);
    const auto json = nlohmann::json::parse(r.output);
    CHECK(json["metric"] == "relmse");
    CHECK(json["value"].get<double>() == Approx(relmse).epsilon(1e-5));
    CHECK(json["passed"] == true);
    for (const char* m : {"rmse", "mae", "relmse", "smape"}) {
      CHECK(json["overall"].contains(m));
      for (const char* c : {"R", "G", "B"}) CHECK(json["channels"][c].contains(m));
    }
    CHECK(json["channels"]["G"]["mae"].get<double>() == 0);
    const Image heat = readImage(dir / "heat.png");
    CHECK(heat.width() == 2);
    CHECK(heat.channelCount() == 3);
  }
  SECTION("above the threshold") {
    const test::CliRun r = runLucent("compare " + files + " --metric mae --max-error 0.001");
    CHECK(r.status == 1);
    const auto json = nlohmann::json::parse(r.output);
    CHECK(json["metric"] == "mae");
    CHECK(json["passed"] == false);
  }
  SECTION("no threshold passes an image of finite values") {
    const test::CliRun r = runLucent("compare " + files);
    CHECK(r.status == 0);
    CHECK(nlohmann::json::parse(r.output)["passed"] == true);
  }
  SECTION("NaN or infinite values fail whatever the metric, and are counted") {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    writeExr(makeImage(2, 1, {"R", "G", "B"}, {nan, nan, nan, nan, nan, nan}), dir / "nan.exr");
    writeExr(makeImage(2, 1, {"R", "G", "B"}, {1, 1, 1, 1, kInf, 1}), dir / "inf.exr");
    for (const char* candidate : {"nan.exr", "inf.exr"})
      for (const char* metric : {"smape", "relmse", "rmse", "mae"}) {
        CAPTURE(candidate, metric);
        const test::CliRun r = runLucent("compare " + quoted(dir / candidate) + " " + quoted(dir / "ref.exr") +
                                         " --metric " + metric + " --max-error 1e9");
        CHECK(r.status == 1);
        const auto json = nlohmann::json::parse(r.output);
        CHECK(json["non_finite"] == (std::string(candidate) == "nan.exr" ? 6 : 1));
        CHECK(json["passed"] == false);
      }
    // In the reference they are bad input.
    const test::CliRun r = runLucent("compare " + quoted(dir / "ref.exr") + " " + quoted(dir / "nan.exr"));
    CHECK(r.status == 2);
    CHECK_THAT(r.output, Catch::Contains("NaN or infinite"));
  }
  SECTION("an 8-bit sRGB image is compared as linear values") {
    // A PNG of mid grey holds code 188, which decodes to 0.503; read as stored it is 0.737.
    const Image grey = makeImage(2, 1, {"R", "G", "B"}, {0.5f, 0.5f, 0.5f, 0.5f, 0.5f, 0.5f});
    writeExr(grey, dir / "grey.exr");
    writePng(grey, dir / "grey.png");
    const test::CliRun r = runLucent("compare " + quoted(dir / "grey.png") + " " + quoted(dir / "grey.exr") +
                                     " --metric mae --max-error 0.005");
    CHECK(r.status == 0);
    CHECK(nlohmann::json::parse(r.output)["value"].get<double>() < 0.005);
  }
  SECTION("a heatmap that would overwrite an image compared is refused") {
    const auto before = fs::last_write_time(dir / "ref.exr");
    const test::CliRun r = runLucent("compare " + files + " --heatmap " + quoted(dir / "ref.exr"));
    CHECK(r.status == 2);
    CHECK_THAT(r.output, Catch::Contains("--heatmap"));
    CHECK(fs::last_write_time(dir / "ref.exr") == before);
  }
  SECTION("a device is refused, not read for ever") {
    const test::CliRun r = runLucent("compare /dev/zero " + quoted(dir / "ref.exr"));
    CHECK(r.status == 2);
    CHECK_THAT(r.output, Catch::Contains("/dev/zero") && Catch::Contains("not a regular file"));
  }
  SECTION("a missing file is an error naming it") {
    const test::CliRun r = runLucent("compare " + quoted(dir / "img.exr") + " " +
                                  quoted(dir / "nope.exr") + " --max-error 1");
    CHECK(r.status == 2);
    CHECK_THAT(r.output, Catch::Contains(dir / "nope.exr"));
  }
  SECTION("mismatched sizes are an error") {
    writeExr(Image(3, 1, {"R", "G", "B"}), dir / "small.exr");
    const test::CliRun r =
        runLucent("compare " + quoted(dir / "small.exr") + " " + quoted(dir / "ref.exr"));
    CHECK(r.status == 2);
    CHECK_THAT(r.output, Catch::Contains("3x1") && Catch::Contains("2x1"));
  }
}

namespace {
// An image with R, G, B and variance.R, .G, .B: `mean` plus Gaussian noise of the given variance.
Image noisyImage(int w, int h, const std::function<float(int, int, int)>& mean, float variance, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<float> noise(0.0f, std::sqrt(variance));
  Image image(w, h, {"R", "G", "B", "variance.R", "variance.G", "variance.B"});
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) image.at(x, y, c) = mean(x, y, c) + noise(rng), image.at(x, y, 3 + c) = variance;
  return image;
}
}  // namespace

TEST_CASE("testWithinNoise: the reference plus noise passes, a bias below a pixel's noise fails", "[compare]") {
  // Gaussian noise of a known variance, tested pixel by pixel (blocks of 1): under no difference
  // each pixel's smallest-of-three p-value, times 3, falls below alpha for at most alpha of the
  // pixels (Bonferroni; about 0.01 x 16,384 = 164, binomial standard deviation 13); a bias of 3% of
  // the mean with noise of 10% per pixel is invisible in one pixel (z 0.3) and plain in the whole
  // image's sum (z about 27).
  const int w = 128, h = 128;
  auto mean = [](int x, int y, int c) { return 1.0f + 0.5f * std::sin(0.1f * float(x + 2 * y + c)); };
  const Image reference = noisyImage(w, h, mean, 0.005f, 1);
  const Image candidate = noisyImage(w, h, mean, 0.005f, 2);
  const NoiseTest same = testWithinNoise(candidate, reference, 0.01, 4, 1);
  INFO("rejected at alpha: " << same.blocksRejectedAtAlpha << ", whole image z " << same.regions[0].z);
  CHECK(same.verdict == Verdict::Pass);
  CHECK(same.blocks == same.pixels);
  CHECK(same.blocksRejected == 0);
  CHECK(same.blocksRejectedAtAlpha > 164 - 4 * 13);
  CHECK(same.blocksRejectedAtAlpha < 164 + 4 * 13);
  // Blocks of 8 x 8 (the default): 256 blocks, about 2.6 below alpha (standard deviation 1.6).
  const NoiseTest blocks = testWithinNoise(candidate, reference, 0.01);
  CHECK(blocks.verdict == Verdict::Pass);
  CHECK(blocks.blocks == 256);
  CHECK(blocks.blocksRejectedAtAlpha < 2.6 + 4 * 1.6);
  REQUIRE(same.regions.size() == 17);
  CHECK(same.regions[0].x1 == w);
  CHECK(same.regions[16].x0 == 96);
  CHECK(std::abs(same.regions[0].relativeDifference) < 0.001);
  const Image biased = noisyImage(w, h, [&](int x, int y, int c) { return 1.03f * mean(x, y, c); }, 0.005f, 2);
  const NoiseTest off = testWithinNoise(biased, reference, 0.01, 4, 1);
  CHECK(off.verdict == Verdict::Fail);
  CHECK(off.blocksRejected == 0);  // no single pixel shows it
  CHECK(off.regions[0].rejected);
  CHECK(off.regions[0].relativeDifference == Approx(0.03).margin(0.003));
  // The candidate's own variance counts: without it the same candidate's z grow by sqrt(2).
  CHECK_THROWS_WITH(testWithinNoise(candidate, rgbChannels(reference), 0.01), Catch::Contains("--variance"));
  const NoiseTest withoutVariance = testWithinNoise(rgbChannels(candidate), reference, 0.01, 4, 1);
  CHECK(withoutVariance.noise.source == NoiseSource::Unknown);
  CHECK(withoutVariance.verdict == Verdict::Inconclusive);
  CHECK(withoutVariance.blocksRejectedAtAlpha > same.blocksRejectedAtAlpha);
}

TEST_CASE("testWithinNoise with runs: one firefly does not raise every pixel's variance floor and hide a bias", "[compare]") {
  // Two runs of 10% noise per pixel against a reference of 64 times their samples, a 3% bias in
  // the sixth region (x 32-63, y 32-63: its sum's z about 14), and in run 1 one white pixel of
  // another region 200 times too bright, as a firefly of a rare path is. Measured over the whole
  // image, the floor on each pixel's variance (the runs' spread over the reference's variance)
  // was 240 times a pixel's own variance everywhere, and the bias passed (z 1.8); capped at 4
  // times the tiles' median it is found (z 9.9). The firefly, alone, is within its own spread.
  const int w = 128, h = 128;
  auto mean = [](int x, int y, int c) { return 1.0f + 0.5f * std::sin(0.1f * float(x + 2 * y + c)); };
  auto biasedMean = [&](int x, int y, int c) {
    return (x >= 32 && x < 64 && y >= 32 && y < 64 ? 1.03f : 1.0f) * mean(x, y, c);
  };
  const Image reference = noisyImage(w, h, mean, 0.005f / 64, 1);
  for (const bool biased : {false, true}) {
    std::vector<Image> runs;
    for (uint64_t seed : {2, 3}) runs.push_back(rgbChannels(noisyImage(
          w, h, [&](int x, int y, int c) { return biased ? biasedMean(x, y, c) : mean(x, y, c); }, 0.005f, seed)));
    for (int c = 0; c < 3; ++c) runs[0].at(100, 110, c) = 200.0f;
    const NoiseTest t = testWithinNoise(Candidate(std::move(runs)), reference, 0.01);
    INFO((biased ? "biased" : "unbiased") << ": region 6's z " << t.regions[6].z << ", region 16's " << t.regions[16].z);
    CHECK(t.noise.source == NoiseSource::Runs);
    CHECK(t.verdict == (biased ? Verdict::Fail : Verdict::Pass));
    CHECK(t.regions[6].rejected == biased);
    CHECK_FALSE(t.regions[16].rejected);
    if (biased) CHECK(t.regions[6].relativeDifference == Approx(0.03).margin(0.005));
  }
}

TEST_CASE("testWithinNoise with runs: where a candidate is quieter than elsewhere, its own variance decides", "[compare]") {
  // Two runs against a reference of 64 times their samples in the left half and 6,400 times in the
  // right (as adaptive sampling, or another renderer's better strategy there, makes a candidate),
  // and a 0.3% bias in the right half's region x 96-127, y 32-63 (z about 19 by its own noise).
  // The image's ratio of the runs' variance to the reference's (about half the left half's) as
  // every pixel's floor made the right half's variance 50 times its own, and the bias passed; the
  // floor now counts at most 4 times each tile's own ratio.
  const int w = 128, h = 128;
  auto mean = [](int x, int y, int c) { return 1.0f + 0.5f * std::sin(0.1f * float(x + 2 * y + c)); };
  const Image reference = noisyImage(w, h, mean, 0.005f / 64, 1);
  std::vector<Image> runs;
  for (uint64_t seed : {2, 3}) {
    const Image left = noisyImage(w, h, mean, 0.005f, seed);
    const Image right = noisyImage(w, h, [&](int x, int y, int c) { return (y >= 32 && y < 64 && x >= 96 ? 1.003f : 1.0f) * mean(x, y, c); },
                                   0.005f / 100, seed + 10);
    Image run = rgbChannels(left);
    for (int y = 0; y < h; ++y)
      for (int x = w / 2; x < w; ++x)
        for (int c = 0; c < 3; ++c) run.at(x, y, c) = right.at(x, y, c);
    runs.push_back(std::move(run));
  }
  const NoiseTest t = testWithinNoise(Candidate(std::move(runs)), reference, 0.01);
  INFO("region 8's z " << t.regions[8].z);
  CHECK(t.verdict == Verdict::Fail);
  CHECK(t.regions[8].rejected);
  for (size_t k : {1, 2, 5, 6, 16}) CHECK_FALSE(t.regions[k].rejected);
}

TEST_CASE("testWithinNoise with variance layers: correlated neighbours leave a failure to runs unless it is gross, "
          "overstated layers a pass", "[compare]") {
  const int w = 64, h = 64;
  auto mean = [](int x, int y, int c) { return 1.0f + 0.5f * std::sin(0.1f * float(x + 2 * y + c)); };
  const Image reference = noisyImage(w, h, mean, 0.01f / 64, 1);
  // Each pixel's noise the mean of a 3 x 3 window of white noise (10% of the mean): neighbours
  // share 6 of 9 cells (rho 0.67), a region's sum varies 9 times what the layers say.
  const auto splatted = [&](float bias, uint64_t seed = 7) {
    std::mt19937_64 rng(seed);
    std::normal_distribution<float> white(0.0f, 1.0f);
    std::vector<float> field(size_t(w + 2) * size_t(h + 2) * 3);
    for (float& f : field) f = white(rng);
    Image image(w, h, {"R", "G", "B", "variance.R", "variance.G", "variance.B"});
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        for (int c = 0; c < 3; ++c) {
          float shared = 0;
          for (int dy = 0; dy < 3; ++dy)
            for (int dx = 0; dx < 3; ++dx) shared += field[(size_t(y + dy) * size_t(w + 2) + size_t(x + dx)) * 3 + size_t(c)] / 3;
          const float m = mean(x, y, c) * (x >= 16 && x < 32 && y >= 16 && y < 32 ? 1 + bias : 1.0f);
          image.at(x, y, c) = m + 0.1f * m * shared, image.at(x, y, 3 + c) = 0.01f * m * m;
        }
    return image;
  };
  const NoiseTest correct = testWithinNoise(splatted(0), reference, 0.01);
  INFO("rho " << correct.noise.neighbourCorrelation << ", z " << correct.noise.neighbourCorrelationZ);
  CHECK(correct.noise.neighbourCorrelation == Approx(0.67).margin(0.05));
  CHECK(correct.verdict != Verdict::Fail);
  // 20% bright in one region: z 32 by the layers, 11 by the true noise, 7.8 with every variance
  // neighbourInflation = 1 + 24 rho = 17 times as large (pixels 3 apart share nothing): it fails.
  CHECK(testWithinNoise(splatted(0.2f), reference, 0.01).verdict == Verdict::Fail);
  // --within's intervals across the margin, correlation shown: runs decide it, not more samples
  // (which would narrow intervals already too narrow). Each pixel's noise shares 0.35 of its right
  // neighbour's white noise (rho 0.31 across x), so sums vary about 1.6 times what the layers say;
  // at alpha 1e-4 no interval of this seed lies beyond a margin of 1e-6, every one reaches across it
  // (one beyond it would be a failure, voided with the same advice).
  const auto shared = [&] {
    std::mt19937_64 rng(11);
    std::normal_distribution<float> white(0.0f, 1.0f);
    std::vector<float> field(size_t(w + 1) * size_t(h) * 3);
    for (float& f : field) f = white(rng);
    Image image(w, h, {"R", "G", "B", "variance.R", "variance.G", "variance.B"});
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        for (int c = 0; c < 3; ++c) {
          const size_t i = (size_t(y) * size_t(w + 1) + size_t(x)) * 3 + size_t(c);
          const float m = mean(x, y, c);
          image.at(x, y, c) = m + 0.1f * m * (field[i] + 0.35f * field[i + 3]) / std::sqrt(1.1225f);
          image.at(x, y, 3 + c) = 0.01f * m * m;
        }
    return image;
  }();
  const EquivalenceTest across = testEquivalence(Candidate(shared), reference, 1e-6, 1e-4);
  INFO(across.noise.undecided);
  CHECK(across.noise.neighbourCorrelation > 0.05);
  CHECK(across.verdict == Verdict::Inconclusive);
  CHECK_THAT(across.noise.undecided, Catch::Contains("correlated") && Catch::Contains("give two or more runs"));
  CHECK_THAT(across.noise.undecided, !Catch::Contains("times the candidate's samples"));
  // By surface (a material per quadrant, and all but emitters): the correct image's intervals cover
  // no difference as often as variances neighbourInflation (1 + 24 rho) times the layers' make them. A sum's true
  // variance is 9 times the layers' per channel, and R + G + B's is bounded as if its channels
  // were fully correlated (3 times the independent channels' variance): by the layers alone 16 of
  // 40 seeds' 200 intervals at 98% missed 0; with both variances 17 times as large they reach more
  // than 5 of the sums' true deviations (at most 2 misses allowed). 20% bright in one quadrant is
  // still found there.
  Image surfaces(w, h, {"R", "G", "B", "variance.R", "variance.G", "variance.B", "surface.material", "surface.emitter"});
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      for (int c = 0; c < 6; ++c) surfaces.at(x, y, c) = reference.at(x, y, c);
      surfaces.at(x, y, 6) = float(2 * (y >= h / 2) + (x >= w / 2)), surfaces.at(x, y, 7) = 0;
    }
  int missed = 0;
  for (uint64_t seed = 20; seed < 60; ++seed)
    for (const SurfaceDifference& d : differenceBySurface(Candidate(splatted(0, seed)), surfaces, {}, 0.01))
      missed += d.low > 0 || d.high < 0;
  CHECK(missed <= 2);
  Image brightQuadrant = splatted(0);
  for (int y = 0; y < h / 2; ++y)
    for (int x = 0; x < w / 2; ++x)
      for (int c = 0; c < 3; ++c) brightQuadrant.at(x, y, c) *= 1.2f;
  const std::vector<SurfaceDifference> located = differenceBySurface(Candidate(brightQuadrant), surfaces, {}, 0.01);
  REQUIRE(located.size() == 5);
  CHECK(located[0].name == "material 0");
  CHECK(located[0].low > 0.1);
  // Layers 16 times the noise (a renderer writing its samples' variance, not its mean's) hide a 2%
  // bias over the whole image (z 12.8 by the true noise, 3.2 by the layers): a pass is inconclusive.
  Image overstated = noisyImage(w, h, [&](int x, int y, int c) { return 1.02f * mean(x, y, c); }, 0.01f, 2);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 3; c < 6; ++c) overstated.at(x, y, c) *= 16;
  const NoiseTest hidden = testWithinNoise(overstated, reference, 0.01);
  INFO(hidden.noise.undecided);
  CHECK(hidden.noise.layerLevel == Approx(1.0 / 16).margin(0.03));
  CHECK(hidden.verdict == Verdict::Inconclusive);
  CHECK_THAT(hidden.noise.undecided, Catch::Contains("larger than"));
  // Layers 1.3 times the noise make the correlation positive at every lag (about 0.23): the
  // squares' level counts the 24 nearest pixels only (z -9.0), not the farther lags that the
  // inflation adds (68.8 here against 6.5: z -2.8, and the pass would stand).
  Image mildly = noisyImage(w, h, mean, 0.01f, 4);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 3; c < 6; ++c) mildly.at(x, y, c) *= 1.3f;
  const NoiseTest mild = testWithinNoise(mildly, reference, 0.01);
  INFO(mild.noise.undecided);
  CHECK(mild.noise.neighbourInflation > 1 + 24 * mild.noise.neighbourCorrelation);
  CHECK(mild.verdict == Verdict::Inconclusive);
  CHECK_THAT(mild.noise.undecided, Catch::Contains("larger than"));
  // Layers that fit pass as they did.
  CHECK(testWithinNoise(noisyImage(w, h, mean, 0.01f, 3), reference, 0.01).verdict == Verdict::Pass);
}

TEST_CASE("testWithinNoise: a variance it cannot trust or identical runs leave it undecided, rounding is no difference",
          "[compare]") {
  const int w = 32, h = 32;
  auto mean = [](int x, int y, int c) { return 1.0f + 0.5f * std::sin(0.1f * float(x + 2 * y + c)); };
  const Image reference = noisyImage(w, h, mean, 0.005f, 1);
  // Infinite variances (a pixel of fewer than 2 samples) would test any difference against
  // infinity: a candidate half as bright again passed. Now: inconclusive, naming the first.
  Image unknown = noisyImage(w, h, [&](int x, int y, int c) { return 1.5f * mean(x, y, c); }, 0.005f, 2);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) unknown.at(x, y, 3) = std::numeric_limits<float>::infinity();
  NoiseTest t = testWithinNoise(unknown, reference, 0.01);
  CHECK(t.verdict == Verdict::Inconclusive);
  CHECK_THAT(t.noise.undecided, Catch::Contains("the image's variance is infinite, NaN or negative at 1024 values (the first at x 0, y 0)"));
  // One NaN (another renderer's M2 / (n - 1) at n = 1) and a negative variance, in a correct candidate.
  Image nan = noisyImage(w, h, mean, 0.005f, 2);
  nan.at(5, 7, 4) = std::numeric_limits<float>::quiet_NaN();
  nan.at(9, 7, 5) = -1e-3f;
  t = testWithinNoise(nan, reference, 0.01);
  CHECK(t.verdict == Verdict::Inconclusive);
  CHECK_THAT(t.noise.undecided, Catch::Contains("the image's variance") && Catch::Contains("at 2 values (the first at x 5, y 7)"));
  // The reference's too.
  Image badReference = reference;
  badReference.at(3, 30, 3) = std::numeric_limits<float>::infinity();
  t = testWithinNoise(noisyImage(w, h, mean, 0.005f, 2), badReference, 0.01);
  CHECK(t.verdict == Verdict::Inconclusive);
  CHECK_THAT(t.noise.undecided, Catch::Contains("the reference's variance") && Catch::Contains("at 1 value (the first at x 3, y 30)"));
  // Runs that are one image (one seed) have no spread: unknown noise, not a noise-free candidate.
  const Image run = rgbChannels(noisyImage(w, h, mean, 0.005f, 3));
  t = testWithinNoise(Candidate(std::vector<Image>{run, run, run}), reference, 0.01);
  CHECK(t.verdict == Verdict::Inconclusive);
  CHECK_THAT(t.noise.undecided, Catch::Contains("the same image"));

  // Where neither image has noise (an emitter seen directly), a difference within the values'
  // rounding counts as none: two units in the last place of 17, and 0.7 stored as a half float
  // (0.7001953125); 1e-4 of 17 is a difference.
  const auto flat = [&](float value) {
    Image image(w, h, {"R", "G", "B", "variance.R", "variance.G", "variance.B"});
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        for (int c = 0; c < 3; ++c) image.at(x, y, c) = value;
    return image;
  };
  const float ulps = std::nextafter(std::nextafter(17.0f, 18.0f), 18.0f);
  CHECK(testWithinNoise(flat(ulps), flat(17.0f), 0.01).verdict == Verdict::Pass);
  CHECK(testWithinNoise(flat(17.0f * (1 + 1e-4f)), flat(17.0f), 0.01).verdict == Verdict::Fail);
  Candidate halves(flat(0.7001953125f));
  CHECK(testWithinNoise(halves, flat(0.7f), 0.01).verdict == Verdict::Fail);  // as 32-bit floats: a difference
  halves.rounding = {{ColourEncoding::Half}};
  CHECK(testWithinNoise(halves, flat(0.7f), 0.01).verdict == Verdict::Pass);
  halves.runs[0] = flat(0.7f * (1 + 1e-3f));
  CHECK(testWithinNoise(halves, flat(0.7f), 0.01).verdict == Verdict::Fail);  // beyond a half's rounding
  // Pixel by pixel: a bright exact emitter (5e4, a quarter of the image) lends no allowance to the
  // noisy pixels beside it, whose 5% bias fails (their sum 0.2 x 768, the emitter's allowance
  // 5e4 x 256 x 2^-11 = 6,250, would have hidden it); a correct candidate passes.
  const auto lamp = [&](float bias, uint64_t seed) {
    Image image = noisyImage(w, h, [&](int, int, int) { return 0.2f * bias; }, 1e-4f, seed);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < 8; ++x)
        for (int c = 0; c < 3; ++c) image.at(x, y, c) = 5e4f, image.at(x, y, 3 + c) = 0;
    return image;
  };
  Candidate lit(lamp(1.05f, 2));
  lit.rounding = {{ColourEncoding::Half}};
  CHECK(testWithinNoise(lit, lamp(1, 1), 0.01).verdict == Verdict::Fail);
  lit.runs[0] = lamp(1, 2);
  CHECK(testWithinNoise(lit, lamp(1, 1), 0.01).verdict == Verdict::Pass);
  // An infinite pixel is a difference no noise or rounding explains.
  Image infinite = noisyImage(w, h, mean, 0.005f, 2);
  infinite.at(7, 7, 1) = std::numeric_limits<float>::infinity();
  t = testWithinNoise(infinite, reference, 0.01);
  CHECK(t.verdict == Verdict::Fail);
  CHECK(t.regions[0].rejected);

  // A shift of colour that keeps R + G + B (red up 10%, blue down 10% on grey): --within judges
  // each channel (it passed on the sum), --test names the channel it rejects.
  auto grey = [](int x, int y, int) { return 1.0f + 0.5f * std::sin(0.1f * float(x + 2 * y)); };
  const Image greyReference = noisyImage(w, h, grey, 0.0005f, 1);
  const Image shifted = noisyImage(w, h, [&](int x, int y, int c) { return grey(x, y, c) * (c == 0 ? 1.1f : c == 2 ? 0.9f : 1.0f); },
                                   0.0005f, 2);
  const EquivalenceTest within = testEquivalence(shifted, greyReference, 0.05, 0.01);
  CHECK(within.verdict == Verdict::Fail);
  CHECK(within.regions[0].channel != 1);
  CHECK(std::abs(within.regions[0].relativeDifference) == Approx(0.1).margin(0.01));
  CHECK(testEquivalence(noisyImage(w, h, grey, 0.0005f, 2), greyReference, 0.05, 0.01).verdict == Verdict::Pass);
  const NoiseTest shift = testWithinNoise(shifted, greyReference, 0.01);
  CHECK(shift.verdict == Verdict::Fail);
  CHECK(std::abs(shift.regions[0].relativeDifference) < 0.01);
  CHECK(shift.regions[0].channel != 1);
  CHECK(std::abs(shift.regions[0].channelDifference) == Approx(0.1).margin(0.01));
  // Where p-values underflow to 0 (|z| beyond 38) the channel named is the one of the largest |z|:
  // red 50% bright (z about 11,000), blue 1% (z about 230).
  const Image apart = noisyImage(w, h, [&](int x, int y, int c) { return grey(x, y, c) * (c == 0 ? 1.5f : c == 2 ? 1.01f : 1.0f); },
                                 1e-6f, 2);
  const NoiseTest far = testWithinNoise(apart, noisyImage(w, h, grey, 1e-6f, 1), 0.01);
  CHECK(far.regions[0].pValue == 0);
  CHECK(far.regions[0].channel == 0);
  CHECK(far.regions[0].channelDifference == Approx(0.5).margin(0.01));

  // Tiles are named by the pixels summed in them: at 10 pixels and 4 tiles, x 0-2, 3-4, 5-7, 8-9.
  const NoiseTest narrow = testWithinNoise(noisyImage(10, 10, mean, 0.005f, 2), noisyImage(10, 10, mean, 0.005f, 1), 0.01);
  REQUIRE(narrow.regions.size() == 17);
  for (int t = 0; t < 4; ++t) {
    CHECK(narrow.regions[size_t(1 + t)].x0 == std::array{0, 3, 5, 8}[size_t(t)]);
    CHECK(narrow.regions[size_t(1 + t)].x1 == std::array{3, 5, 8, 10}[size_t(t)]);
  }
}

TEST_CASE("lucent compare allows for a file's half-float colour channels", "[compare][cli]") {
  // Flat 0.7 with no noise in either image (an emitter seen directly): the candidate's R, G, B
  // stored as half floats (0.7001953125) pass; the same values written as 32-bit floats differ.
  test::TempDir dir("compare-half");
  const int w = 16, h = 16;
  Image flat(w, h, {"R", "G", "B", "variance.R", "variance.G", "variance.B"});
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) flat.at(x, y, c) = 0.7f;
  writeExr(flat, dir / "reference.exr");
  {
    Imf::Header header(w, h);
    Imf::FrameBuffer frame;
    std::vector<half> colour(size_t(w * h), half(0.7f));
    std::vector<float> nought(size_t(w * h), 0.0f);
    for (const char* name : {"R", "G", "B"}) {
      header.channels().insert(name, Imf::Channel(Imf::HALF));
      frame.insert(name, Imf::Slice(Imf::HALF, (char*)colour.data(), sizeof(half), sizeof(half) * size_t(w)));
    }
    for (const char* name : {"variance.R", "variance.G", "variance.B"}) {
      header.channels().insert(name, Imf::Channel(Imf::FLOAT));
      frame.insert(name, Imf::Slice(Imf::FLOAT, (char*)nought.data(), sizeof(float), sizeof(float) * size_t(w)));
    }
    Imf::OutputFile out((dir / "half.exr").c_str(), header);
    out.setFrameBuffer(frame);
    out.writePixels(h);
  }
  writeExr(readImage(dir / "half.exr"), dir / "float.exr");
  const std::string reference = " " + quoted(dir / "reference.exr") + " --test";
  const test::CliRun halfRun = runLucent("compare " + quoted(dir / "half.exr") + reference);
  INFO(halfRun.output);
  CHECK(halfRun.status == 0);
  const test::CliRun floatRun = runLucent("compare " + quoted(dir / "float.exr") + reference);
  INFO(floatRun.output);
  CHECK(floatRun.status == 1);
  // R and G half, B a 32-bit unsigned integer (EXR may mix them): rounded as half floats, the
  // coarser, not as integer codes.
  {
    Imf::Header header(w, h);
    Imf::FrameBuffer frame;
    std::vector<half> colour(size_t(w * h), half(0.7f));
    std::vector<uint32_t> codes(size_t(w * h), 3006477107u);  // 0.7 of 2^32 - 1
    for (const char* name : {"R", "G"}) {
      header.channels().insert(name, Imf::Channel(Imf::HALF));
      frame.insert(name, Imf::Slice(Imf::HALF, (char*)colour.data(), sizeof(half), sizeof(half) * size_t(w)));
    }
    header.channels().insert("B", Imf::Channel(Imf::UINT));
    frame.insert("B", Imf::Slice(Imf::UINT, (char*)codes.data(), sizeof(uint32_t), sizeof(uint32_t) * size_t(w)));
    Imf::OutputFile out((dir / "mixed.exr").c_str(), header);
    out.setFrameBuffer(frame);
    out.writePixels(h);
  }
  CHECK(readImageHeader(dir / "mixed.exr").colourEncoding == ColourEncoding::Half);
  CHECK(readImageHeader(dir / "mixed.exr").largestCode == 0);
}

namespace {
// Writes R, G, B as Radiance RGBE the way stb_image_write and Radiance's own writer do: 8-bit
// mantissas under the pixel's largest channel's exponent, truncated; flat scanlines.
void writeTruncatedRgbe(const Image& image, const fs::path& path) {
  std::ofstream out(path, std::ios::binary);
  out << "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y " << image.height() << " +X " << image.width() << "\n";
  for (int y = 0; y < image.height(); ++y)
    for (int x = 0; x < image.width(); ++x) {
      const float largest = std::max({image.at(x, y, 0), image.at(x, y, 1), image.at(x, y, 2)});
      unsigned char rgbe[4] = {0, 0, 0, 0};
      if (largest > 1e-32f) {
        int exponent = 0;
        const float scale = std::frexp(largest, &exponent) * 256.0f / largest;
        for (int c = 0; c < 3; ++c) rgbe[c] = static_cast<unsigned char>(image.at(x, y, c) * scale);
        rgbe[3] = static_cast<unsigned char>(exponent + 128);
      }
      out.write(reinterpret_cast<const char*>(rgbe), 4);
    }
}

// Writes an uncompressed RGB TIFF of `bits` bits a sample (12: packed, as scanners and film
// pipelines write them; 16, signed where `signedCodes`), every sample the integer code `code`.
void writeTiffCodes(const fs::path& path, int w, int h, int bits, bool signedCodes, int code) {
  std::vector<unsigned char> pixels;
  for (int y = 0; y < h; ++y) {
    uint64_t buffer = 0;
    int held = 0;  // bits in the buffer, packed from the most significant; rows end on a byte
    for (int sample = 0; sample < 3 * w; ++sample) {
      // Packed samples run from the most significant bit; 16-bit ones are in the file's byte order.
      const uint32_t stored = uint32_t(code) & ((1u << bits) - 1);
      buffer = (buffer << bits) | (bits == 16 ? (stored >> 8) | ((stored & 0xff) << 8) : stored);
      for (held += bits; held >= 8; held -= 8) pixels.push_back((unsigned char)(buffer >> (held - 8)));
    }
    if (held > 0) pixels.push_back((unsigned char)(buffer << (8 - held)));
  }
  std::vector<unsigned char> file;
  const auto put = [&](uint32_t v, int bytes) {
    for (int i = 0; i < bytes; ++i) file.push_back((unsigned char)(v >> (8 * i)));
  };
  const uint16_t format = signedCodes ? 2 : 1;
  // Tag, type (3 short, 4 long), count, value; counts of 3 point past the directory (extra).
  const std::vector<std::array<uint32_t, 4>> entries = {
      {256, 4, 1, uint32_t(w)}, {257, 4, 1, uint32_t(h)}, {258, 3, 3, 0}, {259, 3, 1, 1}, {262, 3, 1, 2},
      {273, 4, 1, 0},           {277, 3, 1, 3},           {278, 4, 1, uint32_t(h)}, {279, 4, 1, uint32_t(pixels.size())},
      {284, 3, 1, 1},           {339, 3, 3, 0}};
  const uint32_t directory = 8, extra = directory + 2 + 12 * uint32_t(entries.size()) + 4, data = extra + 12;
  file.insert(file.end(), {'I', 'I', 42, 0});
  put(directory, 4);
  put(uint32_t(entries.size()), 2);
  for (const auto& [tag, type, count, value] : entries) {
    put(tag, 2), put(type, 2), put(count, 4);
    put(tag == 258 ? extra : tag == 339 ? extra + 6 : tag == 273 ? data : value, 4);
  }
  put(0, 4);
  for (int i = 0; i < 3; ++i) put(uint32_t(bits), 2);
  for (int i = 0; i < 3; ++i) put(format, 2);
  file.insert(file.end(), pixels.begin(), pixels.end());
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(file.data()), std::streamsize(file.size()));
}

// Writes an uncompressed palette TIFF of `bits`-bit indices (rows padded to a byte), pixel (x, y)
// showing entry index(x, y) of the palette, whose 16-bit entries are `levels` x 257 (8-bit code
// v as 16 bits: read as v / 255 whichever way a reader narrows them).
void writePaletteTiff(const fs::path& path, int w, int h, int bits, const std::function<int(int, int)>& index,
                      const std::vector<std::array<uint16_t, 3>>& levels) {
  std::vector<unsigned char> pixels;
  for (int y = 0; y < h; ++y) {
    uint32_t buffer = 0;
    int held = 0;
    for (int x = 0; x < w; ++x) {
      buffer = (buffer << bits) | uint32_t(index(x, y));
      for (held += bits; held >= 8; held -= 8) pixels.push_back((unsigned char)(buffer >> (held - 8)));
    }
    if (held > 0) pixels.push_back((unsigned char)(buffer << (8 - held)));
  }
  std::vector<unsigned char> file;
  const auto put = [&](uint32_t v, int bytes) {
    for (int i = 0; i < bytes; ++i) file.push_back((unsigned char)(v >> (8 * i)));
  };
  const uint32_t entries = 1u << bits;
  const std::vector<std::array<uint32_t, 4>> tags = {
      {256, 4, 1, uint32_t(w)}, {257, 4, 1, uint32_t(h)}, {258, 3, 1, uint32_t(bits)}, {259, 3, 1, 1},
      {262, 3, 1, 3},           {273, 4, 1, 0},           {277, 3, 1, 1},                {278, 4, 1, uint32_t(h)},
      {279, 4, 1, uint32_t(pixels.size())},               {320, 3, 3 * entries, 0}};
  const uint32_t directory = 8, colourMap = directory + 2 + 12 * uint32_t(tags.size()) + 4,
                 data = colourMap + 6 * entries;
  file.insert(file.end(), {'I', 'I', 42, 0});
  put(directory, 4);
  put(uint32_t(tags.size()), 2);
  for (const auto& [tag, type, count, value] : tags) {
    put(tag, 2), put(type, 2), put(count, 4);
    put(tag == 320 ? colourMap : tag == 273 ? data : value, 4);
  }
  put(0, 4);
  for (int c = 0; c < 3; ++c)  // the red entries, then the green, then the blue
    for (uint32_t i = 0; i < entries; ++i) put(i < levels.size() ? levels[i][size_t(c)] * 257u : 0u, 2);
  file.insert(file.end(), pixels.begin(), pixels.end());
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(file.data()), std::streamsize(file.size()));
}
}  // namespace

TEST_CASE("lucent compare allows for RGBE's and 8-bit codes' truncation, darker only, and leaves a JPEG undecided",
          "[compare][cli]") {
  // Runs of 0.7 written as RGBE by truncation (0.7's step is 2^-8, so every value falls by 0.2% on
  // average) against a float reference of 0.7 with 0.07% noise, 64 x 64: with 0.3% noise per
  // pixel the fall is 90 times the image's noise, with 5% noise (8 runs) 7 times, and per pixel
  // far below it, where a shift of each pixel's difference by its step left the sum's fall as it
  // was. Allowed over each sum (below by the pixels' steps, above by half) both pass; the same
  // values as 32-bit floats fail; runs 3% bright fail as RGBE.
  test::TempDir dir("compare-rgbe");
  const int w = 64, h = 64;
  const auto flat = [&](float value, float variance, uint64_t seed) {
    return noisyImage(w, h, [&](int, int, int) { return value; }, variance, seed);
  };
  writeExr(flat(0.7f, 0.0005f * 0.0005f, 1), dir / "reference.exr");
  const std::string reference = " " + quoted(dir / "reference.exr") + " --test";
  for (const float noise : {0.002f, 0.035f}) {
    std::string rgbe, floats, bright;
    for (uint64_t seed = 2; seed < (noise < 0.01f ? 4u : 10u); ++seed) {
      const std::string name = "run" + std::to_string(seed);
      writeTruncatedRgbe(flat(0.7f, noise * noise, seed), dir / (name + ".hdr"));
      writeExr(rgbChannels(readImage(dir / (name + ".hdr"))), dir / (name + ".exr"));
      writeTruncatedRgbe(flat(0.7f * 1.03f, noise * noise, seed), dir / (name + "-bright.hdr"));
      rgbe += " " + quoted(dir / (name + ".hdr")), floats += " " + quoted(dir / (name + ".exr"));
      bright += " " + quoted(dir / (name + "-bright.hdr"));
    }
    INFO("noise " << noise);
    CHECK(readImageHeader(dir / "run2.hdr").colourEncoding == ColourEncoding::SharedExponent);
    CHECK(readImageHeader(dir / "run2.exr").colourEncoding == ColourEncoding::Float);
    const test::CliRun asRgbe = runLucent("compare" + rgbe + reference);
    INFO(asRgbe.output);
    CHECK(asRgbe.status == 0);
    const auto rounding = nlohmann::json::parse(asRgbe.output)["stored_rounding"];
    CHECK(rounding["image"].size() == (noise < 0.01f ? 2u : 8u));  // each run's
    for (const auto& run : rounding["image"]) CHECK(run == nlohmann::json::parse(R"({"encoding": "rgbe"})"));
    CHECK(rounding["reference"]["encoding"] == "float");
    const test::CliRun asFloats = runLucent("compare" + floats + reference);
    INFO(asFloats.output);
    CHECK(asFloats.status == 1);
    CHECK(runLucent("compare" + bright + reference).status == 1);
  }
  // No noise (an emitter seen directly), RGBE: 0.705 is stored as 0.703125 (code 180), brighter
  // than 0.7 by more than half a step, which truncation cannot make: a difference; 0.7 itself,
  // stored as 0.69921875, is a step's truncation.
  const auto constant = [&](float value) {  // R, G, B and variance layers of 0
    Image image(w, h, {"R", "G", "B", "variance.R", "variance.G", "variance.B"});
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        for (int c = 0; c < 3; ++c) image.at(x, y, c) = value;
    return image;
  };
  const auto exactRgbe = [&](float value) {
    writeTruncatedRgbe(constant(value), dir / "exact.hdr");
    Image image(w, h, {"R", "G", "B", "variance.R", "variance.G", "variance.B"});
    const Image stored = readImage(dir / "exact.hdr");
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        for (int c = 0; c < 3; ++c) image.at(x, y, c) = stored.at(x, y, c);
    Candidate candidate(std::move(image));
    candidate.rounding = {{ColourEncoding::SharedExponent}};
    return candidate;
  };
  const Image exactReference = constant(0.7f);
  CHECK(testWithinNoise(exactRgbe(0.7f), exactReference, 0.01).verdict == Verdict::Pass);
  CHECK(testWithinNoise(exactRgbe(0.705f), exactReference, 0.01).verdict == Verdict::Fail);

  // 8-bit sRGB codes, no noise: linear 0.5 is stored as code 188 (rounded), read back as 0.50289,
  // within half the code's step (0.0030) above; a truncating writer's code 187 (0.49693) within a
  // step below; 1% beyond either is a difference.
  Image grey(w, h, {"R", "G", "B"});
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) grey.at(x, y, c) = 0.5f;
  writePng(grey, dir / "grey.png");
  CHECK(readImageHeader(dir / "grey.png").colourEncoding == ColourEncoding::Integer);
  CHECK(readImageHeader(dir / "grey.png").largestCode == 255);
  const auto noNoise = [&](const Image& rgb) {  // R, G, B and variance layers of 0
    Image image(w, h, {"R", "G", "B", "variance.R", "variance.G", "variance.B"});
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        for (int c = 0; c < 3; ++c) image.at(x, y, c) = rgb.at(x, y, c);
    return image;
  };
  const Image exact = noNoise(grey);
  Candidate codes(noNoise(readLinearImage(dir / "grey.png")));
  CHECK(testWithinNoise(codes, exact, 0.01).verdict == Verdict::Fail);  // as 32-bit floats
  codes.rounding = {{ColourEncoding::Integer, true, 255}};
  CHECK(testWithinNoise(codes, exact, 0.01).verdict == Verdict::Pass);
  const auto every = [&](Candidate& candidate, float value) {
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        for (int c = 0; c < 3; ++c) candidate.runs[0].at(x, y, c) = value;
  };
  every(codes, 0.50289f * 1.01f);
  CHECK(testWithinNoise(codes, exact, 0.01).verdict == Verdict::Fail);
  every(codes, srgbToLinear(187.0f / 255));
  CHECK(testWithinNoise(codes, exact, 0.01).verdict == Verdict::Pass);
  every(codes, srgbToLinear(187.0f / 255) * 0.99f);
  CHECK(testWithinNoise(codes, exact, 0.01).verdict == Verdict::Fail);

  // A 12-bit TIFF is read as 16-bit codes scaled to their range: its step is 1/4,095, 16 times a
  // 16-bit code's. 0.5 truncated to code 2,047 (0.49988) lies half a step below: within its own
  // step, not a 16-bit one's. Signed 16-bit codes read as code / 32,767.
  writeTiffCodes(dir / "twelve.tif", w, h, 12, false, 2047);
  const ImageHeader twelve = readImageHeader(dir / "twelve.tif");
  CHECK(twelve.colourEncoding == ColourEncoding::Integer);
  CHECK(twelve.largestCode == 4095);
  Candidate twelveBits(noNoise(readImage(dir / "twelve.tif")));
  CHECK(twelveBits.runs[0].at(1, 2, 1) == Approx(2047.0 / 4095).margin(1.0 / 65535));  // through 16 bits
  twelveBits.rounding = {storedRoundingOf(twelve, false)};
  CHECK(testWithinNoise(twelveBits, exact, 0.01).verdict == Verdict::Pass);
  twelveBits.rounding = {{ColourEncoding::Integer, false, 65535}};
  CHECK(testWithinNoise(twelveBits, exact, 0.01).verdict == Verdict::Fail);
  writeTiffCodes(dir / "signed.tif", w, h, 16, true, 16383);
  CHECK(readImageHeader(dir / "signed.tif").largestCode == 32767);
  CHECK(readImage(dir / "signed.tif").at(0, 0, 0) == Approx(16383.0 / 32767).epsilon(1e-6));

  // Runs stored in different ways: their mean is allowed the mean of their allowances. One 8-bit
  // sRGB run and one RGBE run: at linear 0.002 the code's step is 0.00030, RGBE's 2^-16 (0.000015),
  // so their mean may lie 0.00016 low. 0.0001 low passes (not by RGBE's step alone); 0.00025 low
  // fails (the 8-bit step alone, the larger, would pass it).
  const Image dark = constant(0.002f);
  Candidate mixed(constant(0.002f - 0.0001f));
  mixed.rounding = {{ColourEncoding::SharedExponent}};
  CHECK(testWithinNoise(mixed, dark, 0.01).verdict == Verdict::Fail);
  mixed.rounding = {{ColourEncoding::SharedExponent}, {ColourEncoding::Integer, true, 255}};
  CHECK(testWithinNoise(mixed, dark, 0.01).verdict == Verdict::Pass);
  Candidate darker(constant(0.002f - 0.00025f));
  darker.rounding = {{ColourEncoding::SharedExponent}, {ColourEncoding::Integer, true, 255}};
  CHECK(testWithinNoise(darker, dark, 0.01).verdict == Verdict::Fail);
  darker.rounding = {{ColourEncoding::Integer, true, 255}};
  CHECK(testWithinNoise(darker, dark, 0.01).verdict == Verdict::Pass);

  // The breakdown by surface allows for the codes' step too, and gives no interval for a JPEG.
  Image exactSurfaces(w, h, {"R", "G", "B", "variance.R", "variance.G", "variance.B", "surface.material", "surface.emitter"});
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) exactSurfaces.at(x, y, c) = 0.5f;
  every(codes, srgbToLinear(187.0f / 255));  // a truncated code
  const SurfaceDifference stepped = differenceBySurface(codes, exactSurfaces, {}, 0.01)[0];
  INFO(stepped.relativeDifference << ": " << stepped.low << " to " << stepped.high);
  CHECK(stepped.relativeDifference < -0.005);  // within the code's step (0.6% of 0.5)
  CHECK(stepped.low <= 0);
  CHECK(stepped.high >= 0);
  Candidate jpegLike = codes;
  jpegLike.rounding = {{ColourEncoding::Lossy}};
  CHECK(std::isnan(differenceBySurface(jpegLike, exactSurfaces, {}, 0.01)[0].low));

  // A JPEG's compression is no noise: undecided, whatever the values.
  CHECK(readImageHeader(LUCENT_SOURCE_DIR "/scenes/ring/wood-floorboards-texture.jpg").colourEncoding == ColourEncoding::Lossy);
  Candidate lossy(exact);
  lossy.rounding = {{ColourEncoding::Lossy}};
  const NoiseTest t = testWithinNoise(lossy, exact, 0.01);
  CHECK(t.verdict == Verdict::Inconclusive);
  CHECK_THAT(t.noise.undecided, Catch::Contains("JPEG"));
}

TEST_CASE("An image header's half colour channels: R, G, B and layers' colours, not variances", "[compare]") {
  const auto half = [](std::vector<std::string> names) {
    ImageHeader header;
    header.halfChannels = std::move(names);
    return header.hasHalfColour();
  };
  CHECK(half({"R"}));
  CHECK(half({"A", "diffuse.G"}));
  CHECK_FALSE(half({"variance.R", "diffuse.variance.B", "Z", "A"}));
  CHECK_FALSE(half({}));
}

TEST_CASE("testEquivalence: per region, an interval from both images' variance inside the margin", "[compare]") {
  // Gaussian noise of variance 0.001 per channel about a mean near 1, candidate and reference alike,
  // channels independent. A region of 32 x 32 pixels then has the relative standard error 0.1% per
  // channel and image, so each channel's interval is about d +- 2.33 x 0.14%. The candidate scaled by 1.01
  // is within 0.02 and not within 0.005; the unscaled one within 0.02; and over 20 seeds the
  // intervals of all 17 regions cover the true bias 0.01 at least 1 - 2 alpha of the time (336 of
  // 340 expected at the least, 4 standard deviations of the binomial below: 325).
  const int w = 128, h = 128;
  auto mean = [](int x, int y, int c) { return 1.0f + 0.5f * std::sin(0.1f * float(x + 2 * y + c)); };
  auto scaled = [&](int x, int y, int c) { return 1.01f * mean(x, y, c); };
  const Image reference = noisyImage(w, h, mean, 0.001f, 1);
  const EquivalenceTest same = testEquivalence(noisyImage(w, h, mean, 0.001f, 2), reference, 0.02, 0.01);
  CHECK(same.verdict == Verdict::Pass);
  REQUIRE(same.regions.size() == 17);
  CHECK(same.regions[16].x0 == 96);
  int covered = 0, intervals = 0;
  double widest = 0;
  for (uint64_t seed = 2; seed < 22; ++seed) {
    const Image candidate = noisyImage(w, h, scaled, 0.001f, seed);
    const EquivalenceTest tight = testEquivalence(candidate, reference, 0.005, 0.01);
    const EquivalenceTest loose = testEquivalence(candidate, reference, 0.02, 0.01);
    INFO("seed " << seed << ": whole image " << loose.regions[0].relativeDifference << " in [" << loose.regions[0].low
                 << ", " << loose.regions[0].high << "]");
    CHECK(tight.verdict != Verdict::Pass);
    CHECK(loose.verdict == Verdict::Pass);
    for (const EquivalenceRegion& r : loose.regions) {
      covered += r.low < 0.01 && 0.01 < r.high;
      ++intervals;
      widest = std::max(widest, r.high - r.low);
    }
  }
  INFO(covered << " of " << intervals << " intervals cover 0.01; the widest " << widest);
  CHECK(covered >= 325);
  CHECK(widest < 2 * 2.33 * 0.0015);  // each region's interval: about 2 x 2.33 x 0.14%
  // Bad input: the reference's variance is needed, the margin and the significance checked.
  CHECK_THROWS_WITH(testEquivalence(reference, rgbChannels(reference), 0.02, 0.01), Catch::Contains("--variance"));
  CHECK_THROWS(testEquivalence(reference, reference, 0, 0.01));
  CHECK_THROWS(testEquivalence(reference, reference, 0.02, 0.5));
  CHECK(normalUpperQuantile(0.01) == Approx(2.3263478740).epsilon(1e-9));
  CHECK(normalUpperQuantile(0.5) == Approx(0).margin(1e-12));
}

TEST_CASE("lucent compare: a candidate whose noise is unknown is inconclusive (exit 3), runs decide, a terminal gets words",
          "[compare][cli]") {
  test::TempDir dir;
  auto mean = [](int x, int y, int c) { return 1.0f + 0.5f * std::sin(0.1f * float(x + 2 * y + c)); };
  writeExr(noisyImage(64, 64, mean, 0.01f, 1), dir / "reference.exr");
  const Image candidate = noisyImage(64, 64, mean, 0.01f, 2);
  writeExr(candidate, dir / "float.exr");
  writeExr(rgbChannels(candidate), dir / "bare.exr");
  // The same candidate with its variance layers stored as half floats, as an RGBA-and-AOV writer might.
  {
    REQUIRE(candidate.channelCount() == 6);
    Imf::Header header(64, 64);
    Imf::FrameBuffer frame;
    const size_t pixelStride = 6 * sizeof(float);
    std::vector<half> halves(3 * 64 * 64);  // the last three channels, rounded to half floats
    for (size_t i = 0; i < halves.size(); ++i) halves[i] = half(candidate.pixels()[(i % (64 * 64)) * 6 + 3 + i / (64 * 64)]);
    for (int c = 0; c < 6; ++c) {
      const std::string& name = candidate.channels()[size_t(c)];
      if (c < 3) {
        header.channels().insert(name, Imf::Channel(Imf::FLOAT));
        frame.insert(name, Imf::Slice(Imf::FLOAT, (char*)(candidate.pixels().data() + c), pixelStride, pixelStride * 64));
      } else {
        header.channels().insert(name, Imf::Channel(Imf::HALF));
        frame.insert(name, Imf::Slice(Imf::HALF, (char*)(halves.data() + size_t(c - 3) * 64 * 64), sizeof(half),
                                      sizeof(half) * 64));
      }
    }
    Imf::OutputFile out((dir / "half.exr").c_str(), header);
    out.setFrameBuffer(frame);
    out.writePixels(64);
  }
  for (int seed = 3; seed < 7; ++seed) writeExr(rgbChannels(noisyImage(64, 64, mean, 0.01f, uint64_t(seed))), dir / ("run" + std::to_string(seed) + ".exr"));
  const std::string reference = " " + quoted(dir / "reference.exr");
  const test::CliRun withLayer = runLucent("compare " + quoted(dir / "float.exr") + reference + " --test --within 0.05");
  INFO(withLayer.output);
  CHECK(withLayer.status == 0);
  for (const char* name : {"bare.exr", "half.exr"}) {
    const test::CliRun r = runLucent("compare " + quoted(dir / name) + reference + " --test --within 0.05");
    INFO(r.output);
    CHECK(r.status == 3);
    const auto out = nlohmann::json::parse(r.output);
    CHECK(out["verdict"] == "inconclusive");
    CHECK(out["test"]["verdict"] == "inconclusive");
    CHECK(out["equivalence"]["verdict"] == "inconclusive");
    CHECK_THAT(out["test"]["candidate_noise"]["undecided"].get<std::string>(),
               Catch::Contains(std::string(name) == "half.exr" ? "half floats" : "no variance layers"));
  }
  // --max-error alone needs no noise; a failed threshold outweighs an undecided test.
  CHECK(runLucent("compare " + quoted(dir / "bare.exr") + reference + " --max-error 1").status == 0);
  CHECK(runLucent("compare " + quoted(dir / "bare.exr") + reference + " --max-error 1e-9 --test").status == 1);
  // Four runs without variance layers: their spread decides.
  std::string runs;
  for (int seed = 3; seed < 7; ++seed) runs += quoted(dir / ("run" + std::to_string(seed) + ".exr")) + " ";
  const test::CliRun fromRuns = runLucent("compare " + runs + reference.substr(1) + " --test --within 0.05");
  INFO(fromRuns.output);
  CHECK(fromRuns.status == 0);
  const auto out = nlohmann::json::parse(fromRuns.output);
  CHECK(out["runs"].size() == 4);
  CHECK(out["test"]["candidate_noise"]["source"] == "runs");
  CHECK(out["test"]["candidate_noise"]["correlation"]["blocks"]["degrees_of_freedom"] == 3 * 64);
  CHECK(out["test"]["candidate_noise"]["correlation"]["image"]["degrees_of_freedom"] == 3);
  CHECK(runLucent("compare " + runs + reference.substr(1)).status == 2);  // runs need --test or --within
  // At a terminal: the verdict in words (script(1) gives the command a terminal); --json keeps JSON.
  const test::CliRun words = test::runCommand("script -qec " +
                                              quoted(quoted(LUCENT_CLI) + " compare " + quoted(dir / "bare.exr") + reference + " --test") +
                                              " /dev/null");
  INFO(words.output);
  CHECK(words.status == 3);
  CHECK_THAT(words.output, Catch::StartsWith("inconclusive") && Catch::Contains("undecided: the image has no variance layers"));
}

TEST_CASE("lucent compare --test: a path-traced candidate passes its reference, scaled by 1.01 it fails", "[compare][cli]") {
  // The Cornell box at 1,024 samples per pixel, independent samples (the variance of a pixel's mean
  // from its samples' spread), two seeds; then the candidate with every value 1% higher.
  const test::TempDir dir("compare-test");
  auto render = [&](int seed, const std::string& out) {
    const test::CliRun r = runLucent("render " + quoted(LUCENT_SOURCE_DIR "/scenes/cornell-box.json") +
                                     " --spp 1024 --resolution 64x64 --variance --sampler independent --seed " +
                                     std::to_string(seed) + " --quiet -o " + quoted(out));
    INFO(r.output);
    REQUIRE(r.status == 0);
  };
  render(1, dir / "reference.exr");
  render(2, dir / "candidate.exr");
  Image scaled = readImage(dir / "candidate.exr");
  for (int y = 0; y < scaled.height(); ++y)
    for (int x = 0; x < scaled.width(); ++x)
      for (int c = 0; c < 3; ++c)
        scaled.at(x, y, scaled.channelIndex(std::string(1, "RGB"[c]))) *= 1.01f,
            scaled.at(x, y, scaled.channelIndex("variance." + std::string(1, "RGB"[c]))) *= 1.0201f;
  writeExr(scaled, dir / "scaled.exr");
  const test::CliRun pass = runLucent("compare " + quoted(dir / "candidate.exr") + " " + quoted(dir / "reference.exr") +
                                      " --test --heatmap " + quoted(dir / "z.png"));
  INFO(pass.output);
  CHECK(pass.status == 0);
  const auto passed = nlohmann::json::parse(pass.output);
  CHECK(passed["test"]["passed"] == true);
  CHECK(passed["test"]["fraction_rejected_at_alpha"].get<double>() < 0.03);
  CHECK(passed["test"]["block"] == 8);
  CHECK(passed["test"]["blocks"] == 64);  // 64 x 64 pixels in blocks of 8 x 8
  const test::CliRun pixels = runLucent("compare " + quoted(dir / "candidate.exr") + " " + quoted(dir / "reference.exr") +
                                        " --test --block 1");
  INFO(pixels.output);
  REQUIRE(pixels.status <= 1);
  CHECK(nlohmann::json::parse(pixels.output)["test"]["blocks"] == 4096);
  CHECK(runLucent("compare " + quoted(dir / "candidate.exr") + " " + quoted(dir / "reference.exr") + " --test --block 0")
            .status == 2);
  CHECK(std::filesystem::exists(dir / "z.png"));
  const test::CliRun fail = runLucent("compare " + quoted(dir / "scaled.exr") + " " + quoted(dir / "reference.exr") + " --test");
  INFO(fail.output);
  CHECK(fail.status == 1);
  const auto failed = nlohmann::json::parse(fail.output);
  CHECK(failed["test"]["passed"] == false);
  CHECK(failed["test"]["regions"][0]["rejected"] == true);
  CHECK(failed["test"]["regions"][0]["relative_difference"].get<double>() == Approx(0.01).margin(0.004));
  // --within, per channel: the candidate is within 0.04 of the reference (its regions' intervals
  // reach 3.3%: at 64 x 64 and 1,024 samples the blue of a region of 16 x 16 pixels in the tall
  // block's shadow has a relative standard error of 1.2% per image), the scaled one not within
  // 0.005; a photon map is biased by design: it fails --test, and --within tells by how much (the
  // whole image's blue 5% dark, the tall block's shadow's 22% bright, +-3%): within 0.3, not within 0.1.
  // A photon map has no variance layer: one render alone is inconclusive (exit 3), its runs (other
  // seeds) decide.
  const auto within = [&](const std::string& images, const char* margin) {
    const test::CliRun r = runLucent("compare " + images + " " + quoted(dir / "reference.exr") + " --within " + margin);
    INFO(r.output);
    REQUIRE(r.status != 2);
    const auto out = nlohmann::json::parse(r.output);
    CHECK(out["equivalence"]["verdict"] == std::vector<std::string>{"pass", "fail", "", "inconclusive"}[size_t(r.status)]);
    CHECK(out["equivalence"]["regions"].size() == 17);
    return r.status;
  };
  CHECK(within(quoted(dir / "candidate.exr"), "0.04") == 0);
  CHECK(within(quoted(dir / "scaled.exr"), "0.005") == 1);
  std::string pmfgRuns;
  for (int seed = 1; seed <= 4; ++seed) {
    const std::string out = dir / ("pmfg" + std::to_string(seed) + ".exr");
    const test::CliRun pmfg = runLucent("render " + quoted(LUCENT_SOURCE_DIR "/scenes/cornell-box.json") +
                                        " --method pmfg --resolution 64x64 --quiet --seed " + std::to_string(seed) +
                                        " -o " + quoted(out));
    REQUIRE(pmfg.status == 0);
    pmfgRuns += " " + quoted(out);
  }
  const std::string pmfgOne = quoted(dir / "pmfg1.exr");
  const test::CliRun alone = runLucent("compare " + pmfgOne + " " + quoted(dir / "reference.exr") + " --test");
  CHECK(alone.status == 3);
  CHECK_THAT(alone.output, Catch::Contains("no variance layers") && Catch::Contains("runs"));
  CHECK(within(pmfgOne, "0.3") == 3);
  CHECK(runLucent("compare" + pmfgRuns + " " + quoted(dir / "reference.exr") + " --test").status == 1);
  CHECK(within(pmfgRuns, "0.3") == 0);
  CHECK(within(pmfgRuns, "0.1") == 1);
  // A reference without variance layers is bad input (exit 2); --alpha needs --test or --within.
  CHECK(runLucent("compare " + quoted(dir / "candidate.exr") + " " + quoted(dir / "z.png") + " --test").status == 2);
  CHECK(runLucent("compare " + quoted(dir / "candidate.exr") + " " + quoted(dir / "reference.exr") + " --alpha 0.05").status != 0);
  // --variance asks for independent samples.
  CHECK(runLucent("render " + quoted(LUCENT_SOURCE_DIR "/scenes/cornell-box.json") + " --spp 4 --variance -o " +
                  quoted(dir / "x.exr")).status == 1);
}

TEST_CASE("lucent compare says where a difference lies: per material, for emitters and for the rest", "[compare][cli]") {
  // The Cornell box's reference with --layers carries what each pixel's centre shows; four runs of
  // the path tracer (other seeds) have their white walls made 6% dark, as a renderer that weights
  // a diffuse lobe wrongly would: the breakdown finds the white walls -6%, the other walls and the
  // light as they were.
  const test::TempDir dir("compare-surfaces");
  const std::string scene = quoted(LUCENT_SOURCE_DIR "/scenes/cornell-box.json") + " --resolution 64x64 --quiet";
  const test::CliRun reference = runLucent("render " + scene + " --spp 512 --variance --layers --sampler independent "
                                           "--seed 1 -o " + quoted(dir / "reference.exr"));
  INFO(reference.output);
  REQUIRE(reference.status == 0);
  ImageMetadata metadata;
  const Image layers = readImage(dir / "reference.exr", &metadata);
  const std::vector<std::string> names = materialNamesOf(metadata);
  const auto index = [&](const std::string& name) { return float(std::find(names.begin(), names.end(), name) - names.begin()); };
  REQUIRE(index("white") < float(names.size()));
  REQUIRE(index("light") < float(names.size()));
  const int material = layers.channelIndex("surface.material"), emitter = layers.channelIndex("surface.emitter");
  REQUIRE(material >= 0);
  REQUIRE(emitter >= 0);
  int lightPixels = 0;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) {
      const bool light = layers.at(x, y, material) == index("light");
      CHECK((layers.at(x, y, emitter) == 1.0f) == light);  // the light, and only it, emits
      lightPixels += light;
    }
  CHECK(lightPixels > 10);
  std::string runs;
  for (int seed = 2; seed < 6; ++seed) {
    const std::string run = dir / ("run" + std::to_string(seed) + ".exr");
    REQUIRE(runLucent("render " + scene + " --spp 64 --seed " + std::to_string(seed) + " -o " + quoted(run)).status == 0);
    Image image = readImage(run);
    for (int y = 0; y < 64; ++y)
      for (int x = 0; x < 64; ++x)
        if (layers.at(x, y, material) == index("white"))
          for (int c = 0; c < 3; ++c) image.at(x, y, c) *= 0.94f;
    writeExr(image, run);
    runs += quoted(run) + " ";
  }
  const test::CliRun r = runLucent("compare " + runs + quoted(dir / "reference.exr") + " --within 0.05");
  INFO(r.output);
  REQUIRE(r.status != 2);
  const auto out = nlohmann::json::parse(r.output);
  std::map<std::string, nlohmann::json> found;
  for (const auto& entry : out["by_surface"]["surfaces"]) found[entry["name"].get<std::string>()] = entry;
  for (const char* name : {"white", "red", "green", "light", "emitters", "all but emitters"}) REQUIRE(found.count(name));
  auto interval = [&](const char* name) { return std::pair{found[name]["interval"][0].get<double>(), found[name]["interval"][1].get<double>()}; };
  CHECK(found["white"]["relative_difference"].get<double>() == Approx(-0.06).margin(0.01));
  CHECK(interval("white").first <= -0.06);
  CHECK(interval("white").second >= -0.06);
  CHECK(interval("white").second < 0);
  for (const char* name : {"red", "green", "light", "emitters"}) {
    INFO(name);
    CHECK(interval(name).first <= 0);
    CHECK(interval(name).second >= 0);
  }
  CHECK(found["light"]["pixels"] == lightPixels);
  CHECK(found["emitters"]["pixels"] == lightPixels);
  CHECK(interval("all but emitters").second < 0);
  CHECK(found["all but emitters"]["pixels"] == 64 * 64 - lightPixels);
}

TEST_CASE("A correct foreign render, with another pixel filter and noise shared between pixels, passes given its runs",
          "[compare][cli]") {
  // A GPU path tracer's runs as they reach Lucent: its pixel filter a tent of radius 1 (rendered
  // here by Lucent with --pixel-filter tent), its noise correlated between pixels (each run gets a
  // zero-mean field of white noise under a tent of radius 1 pixel, 4% of the pixel, and an offset of
  // 0.5% of the whole image, as a shared random sequence would give) and no variance layer. Given
  // its 8 runs, --test passes it against a tent reference and --within 0.05 does not fail it; a box
  // reference, which every edge of the light tells apart, fails it.
  const test::TempDir dir("compare-foreign");
  const std::string scene = quoted(LUCENT_SOURCE_DIR "/scenes/cornell-box.json") + " --resolution 64x64 --quiet";
  for (const char* filter : {"tent", "box"}) {
    const test::CliRun r = runLucent("render " + scene + " --spp 1024 --sampler independent --variance --seed 1 "
                                     "--pixel-filter " + filter + " -o " + quoted(dir / (std::string(filter) + ".exr")));
    INFO(r.output);
    REQUIRE(r.status == 0);
  }
  std::string runs;
  std::mt19937_64 rng(2024);
  std::normal_distribution<float> normal;
  for (int seed = 2; seed < 10; ++seed) {
    const std::string run = dir / ("run" + std::to_string(seed) + ".exr");
    REQUIRE(runLucent("render " + scene + " --spp 64 --pixel-filter tent --seed " + std::to_string(seed) + " -o " +
                      quoted(run)).status == 0);
    Image image = rgbChannels(readImage(run));
    std::vector<float> field(66 * 66);
    for (float& e : field) e = normal(rng);
    const float offset = 0.005f * normal(rng);
    for (int y = 0; y < 64; ++y)
      for (int x = 0; x < 64; ++x) {
        float shared = 0;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx)
            shared += (dx == 0 ? 0.5f : 0.25f) * (dy == 0 ? 0.5f : 0.25f) * field[size_t((y + 1 + dy) * 66 + x + 1 + dx)];
        for (int c = 0; c < 3; ++c) image.at(x, y, c) *= 1 + 0.04f / 0.375f * shared + offset;
      }
    writeExr(image, run);
    runs += quoted(run) + " ";
  }
  auto verdict = [&](const std::string& reference, const std::string& flags) {
    const test::CliRun r = runLucent("compare " + runs + quoted(dir / reference) + " " + flags);
    INFO(r.output);
    REQUIRE(r.status != 2);
    return r.status;
  };
  CHECK(verdict("tent.exr", "--test") == 0);
  CHECK(verdict("tent.exr", "--within 0.05") != 1);
  CHECK(verdict("box.exr", "--test") == 1);
}

TEST_CASE("A palette TIFF is read: an index a pixel in the file, the palette's 8-bit codes on screen", "[image]") {
  // Uncompressed, its file holds a 4- or 8-bit index a pixel, not three channels' codes (the size
  // check once refused every such file as claiming more than it held), and its colours are the
  // palette's codes, of 8 bits: their step is 1/255 however few bits the index has.
  TempDir dir;
  const std::vector<std::array<uint16_t, 3>> levels = {{0, 0, 0}, {255, 128, 7}, {12, 200, 99}, {77, 77, 250}};
  const auto index = [](int x, int y) { return (x + 2 * y) % 4; };
  for (const int bits : {4, 8}) {
    INFO(bits << "-bit indices");
    const std::string path = dir / ("palette" + std::to_string(bits) + ".tif");
    writePaletteTiff(path, 21, 9, bits, index, levels);
    const ImageHeader header = readImageHeader(path);
    CHECK(header.colourEncoding == ColourEncoding::Integer);
    CHECK(header.largestCode == 255);
    const Image image = readImage(path);
    REQUIRE(image.width() == 21);
    REQUIRE(image.height() == 9);
    uint64_t wrong = 0;
    for (int y = 0; y < 9; ++y)
      for (int x = 0; x < 21; ++x)
        for (int c = 0; c < 3; ++c)
          wrong += std::abs(image.at(x, y, c) - levels[size_t(index(x, y))][size_t(c)] / 255.0f) > 1e-6f;
    CHECK(wrong == 0);
  }
}
