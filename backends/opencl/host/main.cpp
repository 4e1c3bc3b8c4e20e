// lucent-opencl: runs the OpenCL kernels of backends/opencl/kernels on a Lucent dump and compares
// their results with the dump's arrays, on any OpenCL device (PoCL on the CPU, a GPU's driver).
//
//   lucent-opencl layout
//   lucent-opencl knn-grid DUMP_DIR --k K --max-radius R [--map global|caustic] [--band band0]
//   lucent-opencl radiance-cache DUMP_DIR [--max-angle DEGREES]
//   lucent-opencl particles DUMP_DIR
//
// Prints one JSON line and exits 0 when every stage agrees, 1 when one differs, 2 on an error.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <iostream>

#include "dump_kernels.h"

using namespace lucent::opencl;

namespace {

nlohmann::json toJson(const StageCheck& c) {
  nlohmann::json j = {{"stage", c.stage}, {"compared", c.compared}, {"differing", c.differing},
                      {"worst_relative_difference", c.worstRelative}, {"passed", c.passed()}};
  if (c.firstDiffering != SIZE_MAX) j["first_differing"] = c.firstDiffering;
  if (!c.note.empty()) j["note"] = c.note;
  return j;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Runs Lucent's OpenCL kernels on a dump and compares them with the dump's arrays"};
  std::string deviceName, dir, map = "global", band = "band0";
  uint32_t k = 50;
  float maxRadius = 0, maxAngle = 20;
  double tolerance = 1e-5;
  app.add_option("--device", deviceName, "an OpenCL device whose name contains this (default: a GPU if any)");
  app.add_option("--tolerance", tolerance, "relative difference allowed per value (the sums' rounding)")->capture_default_str();
  app.require_subcommand(1);
  app.add_subcommand("layout", "compare the OpenCL C record layout with the C++ one");
  CLI::App* knn = app.add_subcommand("knn-grid", "Purcell's kNN-grid estimate from a --map sort purcell or pmfg dump");
  knn->add_option("dump", dir, "the dump directory")->required()->check(CLI::ExistingDirectory);
  knn->add_option("--k", k, "photons per estimate (the render's k or caustic_k)")->capture_default_str();
  knn->add_option("--max-radius", maxRadius, "the render's maximum search radius (its summary's options)")->required();
  knn->add_option("--map", map, "global or caustic")->check(CLI::IsMember({"global", "caustic"}))->capture_default_str();
  knn->add_option("--band", band, "the band of shading points")->capture_default_str();
  CLI::App* cache = app.add_subcommand("radiance-cache", "the environment-lighting paper's cache interpolation (Eq. 5) from an envpbgi dump");
  cache->add_option("dump", dir, "the dump directory")->required()->check(CLI::ExistingDirectory);
  cache->add_option("--max-angle", maxAngle, "the render's cache_max_angle, degrees")->capture_default_str();
  CLI::App* particles = app.add_subcommand("particles", "the particle-space paper's gathering (R3, R4) from a particles dump");
  particles->add_option("dump", dir, "the dump directory")->required()->check(CLI::ExistingDirectory);
  CLI11_PARSE(app, argc, argv);

  try {
    const Device device(deviceName);
    nlohmann::json out = {{"device", device.name()}, {"platform", device.platform()}};
    // Every run checks the records first: a kernel reading a differently laid-out record is wrong.
    const std::vector<std::string> differences =
        layoutDifferences(cppRecordLayout(), openclRecordLayout(device, std::string(kernelSource("records.cl"))));
    out["layout_differences"] = differences;
    bool passed = differences.empty();
    std::vector<StageCheck> checks;
    if (*knn) {
      const KnnGridRun run = runKnnGridEstimate(device, dir, map, band, k, maxRadius);
      checks.push_back(checkKnnGridEstimate(run, dir, map, band, tolerance));
    } else if (*cache) {
      checks.push_back(checkCacheInterpolation(runCacheInterpolation(device, dir, maxAngle), dir, tolerance));
    } else if (*particles) {
      checks = checkParticleGathering(runParticleGathering(device, dir), dir, tolerance);
    }
    out["stages"] = nlohmann::json::array();
    for (const StageCheck& c : checks) out["stages"].push_back(toJson(c)), passed &= c.passed();
    out["passed"] = passed;
    std::cout << out.dump() << "\n";
    return passed ? 0 : 1;
  } catch (const std::exception& e) {
    std::cerr << "lucent-opencl: " << e.what() << "\n";
    return 2;
  }
}
