// lucent-opencl: runs the OpenCL kernels of backends/opencl/kernels on a Lucent dump, writes their
// results as dump arrays into a candidate directory and compares it with the dump as `lucent
// check-dump` does, on any OpenCL device (PoCL on the CPU, a GPU's driver).
//
//   lucent-opencl layout
//   lucent-opencl knn-grid DUMP_DIR --k K --max-radius R [--map global|caustic] [--band band0] [--out DIR]
//   lucent-opencl radiance-cache DUMP_DIR [--max-angle DEGREES] [--out DIR]
//   lucent-opencl particles DUMP_DIR [--out DIR]
//
// Prints one JSON line and exits 0 when the layout and every array agree, 1 when one differs, 2 on
// an error.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <mutex>
#include <random>
#include <thread>

#include "core/json_text.h"
#include "dump_kernels.h"
#include "lucent/core/files.h"
#include "lucent/render/dump_compare.h"

using namespace lucent;
using namespace lucent::opencl;

namespace {

// A directory of the run's own in the temporary directory, removed however the run ends: by its
// end, an error, or SIGINT, SIGTERM or SIGHUP, which may come while a kernel runs for minutes.
// The signals' handler only writes the signal to a pipe (what a handler may do); a thread of its
// own reads it, removes the directory and ends the process by the signal, as its default action
// would have. A signal that comes while a file is written waits for the write (writeFilesAtomically).
class RunDirectory {
 public:
  RunDirectory() {
    if (::pipe2(pipe_, O_CLOEXEC) != 0) throw std::runtime_error(std::string("cannot create a pipe: ") + std::strerror(errno));
    struct sigaction action {};
    action.sa_handler = &RunDirectory::handle;
    sigemptyset(&action.sa_mask);
    for (int signal : {SIGINT, SIGTERM, SIGHUP}) sigaction(signal, &action, nullptr);
    std::thread(&RunDirectory::removeOnSignal).detach();
  }
  RunDirectory(const RunDirectory&) = delete;
  RunDirectory& operator=(const RunDirectory&) = delete;
  ~RunDirectory() { remove(); }

  // A new directory (create_directory is false for one that exists: another name).
  std::string create() {
    State& s = state();
    const std::lock_guard lock(s.mutex);
    std::random_device random;
    do s.path = std::filesystem::temp_directory_path() / ("lucent-opencl-" + std::to_string(random()));
    while (!std::filesystem::create_directory(s.path));
    return s.path.string();
  }

 private:
  static void handle(int signal) {
    const unsigned char byte = static_cast<unsigned char>(signal);
    [[maybe_unused]] const ssize_t written = ::write(pipe_[1], &byte, 1);
  }
  static void removeOnSignal() {
    unsigned char byte = 0;
    while (::read(pipe_[0], &byte, 1) != 1)
      if (errno != EINTR) return;
    remove();
    std::cerr << "lucent-opencl: stopped by " << (byte == SIGINT ? "SIGINT" : byte == SIGHUP ? "SIGHUP" : "SIGTERM") << "\n";
    ::signal(byte, SIG_DFL);
    ::raise(byte);
  }
  static void remove() {
    State& s = state();
    const std::lock_guard lock(s.mutex);
    std::error_code ignored;
    if (!s.path.empty()) std::filesystem::remove_all(s.path, ignored);
    s.path.clear();
  }
  // Never destroyed: the thread may read it while the process exits.
  struct State {
    std::mutex mutex;
    std::filesystem::path path;
  };
  static State& state() {
    static State* s = new State;
    return *s;
  }
  static inline int pipe_[2] = {-1, -1};
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Runs Lucent's OpenCL kernels on a dump and compares their results with the dump's arrays"};
  std::string deviceName, dir, out, map = "global", band = "band0";
  uint32_t k = 50, capacity = 1024;
  float maxRadius = 0, maxAngle = 20;
  DumpCompareOptions compare;
  app.add_option("--device", deviceName, "an OpenCL device whose name contains this (default: a GPU if any)");
  app.add_option("--relative", compare.relative, "relative difference allowed between two floats")
      ->capture_default_str()->check(CLI::Range(0.0, 1.0));
  app.add_option("--ulps", compare.ulps, "or this many units in the last place")->capture_default_str();
  app.require_subcommand(1);
  app.add_subcommand("layout", "compare the OpenCL C record layout with the C++ one");
  CLI::App* knn = app.add_subcommand("knn-grid", "Purcell's kNN-grid estimate from a --map sort purcell or pmfg dump");
  knn->add_option("--k", k, "photons per estimate (the render's k or caustic_k)")->capture_default_str();
  knn->add_option("--max-radius", maxRadius, "the maximum search radius (the render summary's derived.max_radius)")->required();
  knn->add_option("--map", map, "global or caustic")->check(CLI::IsMember({"global", "caustic"}))->capture_default_str();
  knn->add_option("--band", band, "the band of shading points")->capture_default_str();
  knn->add_option("--capacity", capacity, "neighbours kept per point (the device holds points x capacity x 8 bytes)")
      ->capture_default_str()->check(CLI::Range(1u, 1u << 20));
  CLI::App* cache = app.add_subcommand("radiance-cache", "the environment-lighting paper's cache interpolation (Eq. 5) from an envpbgi dump");
  cache->add_option("--max-angle", maxAngle, "the render's cache_max_angle, degrees, in [0.01, 90]")->capture_default_str();
  CLI::App* particles = app.add_subcommand("particles", "the particle-space paper's gathering (R3, R4) from a particles dump");
  for (CLI::App* stage : {knn, cache, particles}) {
    stage->add_option("dump", dir, "the dump directory")->required()->check(CLI::ExistingDirectory);
    stage->add_option("--out", out, "an existing directory for the kernels' arrays (default: a temporary one, removed)")
        ->check(CLI::ExistingDirectory);
  }
  CLI11_PARSE(app, argc, argv);

  try {
    RunDirectory temporary;  // removed when this block ends, by a return or an exception
    // Checked before any work; CLI11's range checks let NaN through.
    checkDumpCompareOptions(compare);
    if (*cache && !(maxAngle >= 0.01f && maxAngle <= 90)) throw std::invalid_argument("--max-angle must lie in [0.01, 90]");
    if (*knn && !(maxRadius > 0 && std::isfinite(maxRadius))) throw std::invalid_argument("--max-radius must be a finite number above 0");
    std::error_code ec;
    if (!out.empty() && std::filesystem::equivalent(out, dir, ec))
      throw std::invalid_argument("--out '" + out + "' is the dump directory it reads; the kernels' arrays would replace "
                                  "the dump's: choose another directory");
    // The dump's arrays are this run's inputs: no write of the kernels' arrays replaces one, by
    // whatever name (a link in --out) it would reach it.
    if (!dir.empty())
      for (const auto& entry : std::filesystem::directory_iterator(dir)) admitInputFile(entry.path());
    const Device device(deviceName);
    nlohmann::json result = {{"device", device.name()}, {"platform", device.platform()}};
    // Every run checks the records first: a kernel reading a differently laid-out record is wrong.
    const std::vector<std::string> differences =
        layoutDifferences(cppRecordLayout(), openclRecordLayout(device, std::string(kernelSource("records.cl"))));
    result["layout_differences"] = differences;
    bool passed = differences.empty();
    if (!dir.empty()) {
      if (out.empty()) out = temporary.create();
      size_t leftToHost = 0;
      if (*knn) leftToHost = writeKnnGridDumps(runKnnGridEstimate(device, dir, map, band, k, maxRadius, capacity), dir, map, band, out);
      if (*cache) leftToHost = writeCacheDumps(runCacheInterpolation(device, dir, maxAngle), dir, out);
      if (*particles) writeParticleDumps(runParticleGathering(device, dir), out);
      const DumpComparison c = compareDumpDirectories(dir, out, compare);
      std::cerr << dumpComparisonReport(c);
      result["left_to_host"] = leftToHost;  // values the kernel does not compute, copied from the dump
      result["comparison"] = nlohmann::json::parse(dumpComparisonJson(c));
      passed = passed && c.passed();
    }
    result["passed"] = passed;
    std::cout << jsonText(result) << "\n";
    return passed ? 0 : 1;
  } catch (const std::exception& e) {
    std::cerr << "lucent-opencl: " << e.what() << "\n";
    return 2;
  }
}
