// The memory limit: sizes as written, the process's memory in use, and renders that would not fit
// refused at once, naming the option to lower, with no output.
#include <catch2/catch.hpp>

#include <chrono>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <vector>

#include "lucent/core/memory.h"
#include "lucent/trace/visibility.h"
#include "test_scenes.h"
#include "test_support.h"

using namespace lucent;

TEST_CASE("Memory sizes are read as the command line writes them", "[memory]") {
  CHECK(parseMemorySize("1000") == 1000);
  CHECK(parseMemorySize("512M") == uint64_t(512) << 20);
  CHECK(parseMemorySize("512m") == uint64_t(512) << 20);
  CHECK(parseMemorySize("1.5G") == uint64_t(3) << 29);
  CHECK(parseMemorySize("8GiB") == uint64_t(8) << 30);
  CHECK(parseMemorySize("2TB") == uint64_t(2) << 40);
  CHECK(parseMemorySize("64K") == 65536);
  for (const char* bad : {"", "G", "12X", "-1", "1.5Gb", "nan", "inf", "1e30T", "5 G", "0x10"}) {
    CAPTURE(bad);
    CHECK_THROWS_AS(parseMemorySize(bad), std::invalid_argument);
  }
  CHECK(memoryText(512) == "512 bytes");
  CHECK(memoryText(1536) == "1.50 KiB");
  CHECK(memoryText(uint64_t(23) << 30) == "23.0 GiB");
}

TEST_CASE("The memory in use follows the process's allocations", "[memory]") {
  const uint64_t before = memoryInUse();
  REQUIRE(before > 0);
  std::vector<char> block(size_t(256) << 20);
  std::memset(block.data(), 1, block.size());  // resident only once touched
  const uint64_t during = memoryInUse();
  CHECK(during >= before + (uint64_t(200) << 20));
  const uint64_t available = availableMemory();
  CHECK(available > 0);
  std::ifstream meminfo("/proc/meminfo");
  std::string key;
  uint64_t totalKib = 0;
  meminfo >> key >> totalKib;
  REQUIRE(key == "MemTotal:");
  CHECK(available <= totalKib * 1024);
}

TEST_CASE("An allocation beyond the limit is refused with the remedy, one within passes", "[memory]") {
  struct RestoreDefault {
    ~RestoreDefault() { setMemoryLimit(0); }
  } restore;
  setMemoryLimit(memoryInUse() + (uint64_t(64) << 20));
  CHECK_NOTHROW(requireMemory(uint64_t(16) << 20, "a small array", "lower --small"));
  try {
    requireMemory(uint64_t(1) << 30, "a large array", "lower --large");
    FAIL("no MemoryLimitError");
  } catch (const MemoryLimitError& e) {
    const std::string message = e.what();
    CHECK_THAT(message, Catch::StartsWith("a large array would need 1.00 GiB") && Catch::Contains("--memory-limit") &&
                            Catch::EndsWith("lower --large"));
  }
  // Beyond 2^64 bytes in all: no wrap-around.
  CHECK_THROWS_AS(requireMemory(UINT64_MAX, "everything", "lower --all"), MemoryLimitError);
  setMemoryLimit(0);
  CHECK(memoryLimit() >= memoryInUse());
}

TEST_CASE("Embree's acceleration structure is held to the memory limit: refused beyond it, built within it",
          "[memory]") {
  // A sphere of 399,200 triangles: Embree's copies of its vertices and indices alone take about 7 MB,
  // its BVH tens more.
  Scene scene;
  Material diffuse;
  test::addSphere(scene, {0, 0, 0}, 1, 500, 400, test::addMaterial(scene, diffuse, "diffuse"));
  scene.camera = test::testCamera({0, 0, 5}, {0, 0, 0}, 8, 8);
  finalizeScene(scene);
  struct RestoreDefault {
    ~RestoreDefault() { setMemoryLimit(0); }
  } restore;
  setMemoryLimit(memoryInUse() + (uint64_t(4) << 20));
  try {
    const Visibility vis(scene);
    FAIL("built beyond the limit");
  } catch (const MemoryLimitError& e) {
    const std::string message = e.what();
    CHECK_THAT(message, Catch::StartsWith("the acceleration structure of the scene's 399200 triangles") &&
                            Catch::Contains("--memory-limit") && Catch::EndsWith("raise --memory-limit"));
  }
  setMemoryLimit(memoryInUse() + (uint64_t(1) << 30));
  const Visibility vis(scene);
  CHECK(vis.intersect(Ray{{0, 0, 5}, {0, 0, -1}}).found());
}

TEST_CASE("render stops at once when the memory it would need exceeds --memory-limit", "[memory][cli][render]") {
  const test::TempDir dir("memory");
  const std::string exr = dir / "out.exr";
  const std::string cornell = LUCENT_SOURCE_DIR "/scenes/cornell-box.json";
  const std::string glass = LUCENT_SOURCE_DIR "/scenes/glass-ball.json";
  struct Case {
    std::string scene, args, remedy;
  };
  for (const Case& c : std::vector<Case>{
           {cornell, "--method purcell --photons 268435456", "lower --photons"},
           {cornell, "--method pmfg --photons 100000000 --gather-rays 4", "lower --photons"},
           {glass, "--method pmfg --photons 1000 --caustic-photons 268435456 --gather-rays 4", "lower --caustic-photons"},
           {cornell, "--method pt --resolution 8000x8000", "lower --resolution"},
           {cornell, "--method micro --points 8388608", "lower --points or raise --point-spacing"},
           {cornell, "--method micro --points 1024 --spp 64 --resolution 2048x2048", "lower --spp or --resolution"},
           {cornell, "--method micro --points 1024 --lighting photons --photons 100000000", "lower --photons"}}) {
    const auto start = std::chrono::steady_clock::now();
    const test::CliRun r = test::runLucent("render " + test::quoted(c.scene) + " " + c.args + " --memory-limit 1G --quiet -o " +
                                     test::quoted(exr));
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    INFO(c.args << ": " << r.output);
    CHECK(r.status == 1);
    CHECK_THAT(r.output, Catch::Contains("--memory-limit") && Catch::Contains(c.remedy));
    CHECK(seconds < 10);
    CHECK(dir.entries().empty());
  }
  const test::CliRun fits = test::runLucent("render " + test::quoted(cornell) +
                                      " --spp 1 --resolution 16x16 --memory-limit 2G --quiet -o " + test::quoted(exr));
  INFO(fits.output);
  REQUIRE(fits.status == 0);
  CHECK(nlohmann::json::parse(fits.output)["memory_limit"] == uint64_t(2) << 30);
  for (const char* bad : {"0", "12X", "-5G"}) {
    const test::CliRun r = test::runLucent("render " + test::quoted(cornell) + " --memory-limit " + bad + " --quiet -o " +
                                     test::quoted(exr));
    CHECK(r.status == 1);
    CHECK_THAT(r.output, Catch::Contains("--memory-limit"));
  }
}
