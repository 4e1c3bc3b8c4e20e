// lucent render SCENE.json --method NAME [options] -o OUT.exr [--png OUT.png]
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cli/commands.h"
#include "cli/progress.h"
#include "lucent/core/parallel.h"
#include "lucent/methods/pathtrace.h"
#include "lucent/scene/loader.h"

namespace lucent::cli {
namespace fs = std::filesystem;

namespace {

struct RenderArgs {
  std::string scene, method = "pt", output, png, resolution, strategy = "mis";
  int threads = 0;
  bool quiet = false, robust = false;
  PathTraceOptions pt;
};

std::string hex(uint64_t v) {
  std::ostringstream s;
  s << std::hex << v;
  return s.str();
}

void checkOutputPath(const std::string& path, const std::string& extension, const std::string& flag) {
  if (fs::path(path).extension() != extension) throw std::invalid_argument(flag + " '" + path + "' must end in " + extension);
  const fs::path dir = fs::absolute(path).parent_path();
  if (!fs::is_directory(dir)) throw std::invalid_argument(flag + ": directory '" + dir.string() + "' does not exist");
}

int runRender(RenderArgs& a) {
  checkOutputPath(a.output, ".exr", "-o");
  if (!a.png.empty()) checkOutputPath(a.png, ".png", "--png");

  Stopwatch total;
  RenderStats stats;
  Stopwatch loadClock;
  Scene scene = loadScene(a.scene, {a.quiet});
  if (!a.resolution.empty()) {
    int w = 0, h = 0;
    char x = 0, rest = 0;
    std::istringstream in(a.resolution);
    if (!(in >> w >> x >> h) || x != 'x' || (in >> rest) || w < 1 || h < 1 || w > 65536 || h > 65536)
      throw std::invalid_argument("--resolution '" + a.resolution + "': expected WIDTHxHEIGHT, e.g. 512x512");
    if (uint64_t(w) * h > kMaxImagePixels)
      throw std::invalid_argument("--resolution '" + a.resolution + "': more than 2^26 pixels");
    scene.camera.width = w;
    scene.camera.height = h;
    scene.contentHash = sceneContentHash(scene);
  }
  stats.addStage("load_scene", loadClock.seconds());

  ParallelScope parallel(a.threads);
  Stopwatch bvhClock;
  VisibilityOptions visOptions;
  visOptions.robust = a.robust;
  const Visibility visibility(scene, visOptions);
  stats.addStage("build_bvh", bvhClock.seconds());

  nlohmann::json options;
  RenderOutput out;
  {
    ProgressBar bar(!a.quiet);
    if (a.method == "pt") {
      a.pt.strategy = a.strategy == "light" ? PathStrategy::LightSampling
                      : a.strategy == "bsdf" ? PathStrategy::BsdfSampling
                                             : PathStrategy::Mis;
      options = {{"spp", a.pt.spp},           {"max_depth", a.pt.maxDepth}, {"roulette_depth", a.pt.rouletteDepth},
                 {"seed", a.pt.seed},         {"time_budget", a.pt.timeBudget}, {"layers", a.pt.layers},
                 {"strategy", a.strategy},    {"robust", a.robust}};
      out = renderPathTraced(scene, visibility, a.pt, [&](double f) { bar.update(f); });
    } else {
      throw std::invalid_argument("--method '" + a.method + "': unknown method (available: pt)");
    }
  }
  for (const auto& s : out.stats.stageSeconds) stats.addStage(s.first, s.second);
  stats.counters = out.stats.counters;
  const double renderSeconds = total.seconds();

  ImageMetadata meta = {{"lucent:method", a.method},
                        {"lucent:options", options.dump()},
                        {"lucent:spp", std::to_string(out.sppDone)},
                        {"lucent:seed", std::to_string(a.pt.seed)},
                        {"lucent:render_seconds", std::to_string(renderSeconds)},
                        {"lucent:version", LUCENT_VERSION},
                        {"lucent:embree_version", Visibility::embreeVersion()},
                        {"lucent:embree_isa", visibility.isa()},
                        {"lucent:scene", fs::absolute(a.scene).lexically_normal().string()},
                        {"lucent:scene_hash", hex(scene.contentHash)},
                        {"lucent:threads", std::to_string(parallel.threads())}};
  Stopwatch writeClock;
  writeExr(out.image, a.output, meta);
  if (!a.png.empty()) writePng(out.image, a.png);
  stats.addStage("write_images", writeClock.seconds());

  nlohmann::json summary;
  summary["method"] = a.method;
  summary["options"] = options;
  summary["spp"] = out.sppDone;
  summary["threads"] = parallel.threads();
  summary["seconds"] = total.seconds();
  for (const auto& [name, seconds] : stats.stageSeconds) summary["stages"][name] = seconds;
  for (const auto& [name, value] : stats.counters) summary["counters"][name] = value;
  summary["output"] = a.output;
  if (!a.png.empty()) summary["png"] = a.png;
  summary["scene_hash"] = hex(scene.contentHash);
  std::cout << summary.dump() << std::endl;
  return 0;
}

}  // namespace

void addRenderCommand(CLI::App& app, int& exitCode) {
  auto args = std::make_shared<RenderArgs>();
  CLI::App* cmd = app.add_subcommand("render", "Render a scene to an EXR (and optionally a PNG)");
  cmd->add_option("scene", args->scene, "Scene file (JSON)")->required();
  cmd->add_option("--method", args->method, "Rendering method: pt")->capture_default_str();
  cmd->add_option("-o,--output", args->output, "Output EXR file")->required();
  cmd->add_option("--png", args->png, "Also write an sRGB PNG");
  cmd->add_option("--spp", args->pt.spp, "Samples per pixel")->check(CLI::Range(1, 1 << 24))->capture_default_str();
  cmd->add_option("--seed", args->pt.seed, "Random seed")->capture_default_str();
  cmd->add_option("--threads", args->threads, "Worker threads (0: all cores)")->check(CLI::Range(0, 4096));
  cmd->add_option("--resolution", args->resolution, "Override the camera resolution, WIDTHxHEIGHT");
  cmd->add_option("--time-budget", args->pt.timeBudget, "Stop sampling within this many seconds (at least 1 spp)")
      ->check(CLI::Range(0.0, 1e9));
  cmd->add_option("--max-depth", args->pt.maxDepth, "Path length in bounces (1: direct light only)")
      ->check(CLI::Range(0, 1 << 16))->capture_default_str();
  cmd->add_option("--roulette-depth", args->pt.rouletteDepth, "Russian roulette from this bounce on")
      ->check(CLI::Range(1, 1 << 16))->capture_default_str();
  cmd->add_option("--tile-size", args->pt.tileSize, "Tile size in pixels (does not change the image)")
      ->check(CLI::Range(1, 4096))->capture_default_str();
  cmd->add_option("--strategy", args->strategy, "pt: mis (default), or light or bsdf sampling alone, for validation")
      ->check(CLI::IsMember({"mis", "light", "bsdf"}));
  cmd->add_flag("--layers", args->pt.layers, "Add albedo, normal, depth, direct and indirect layers to the EXR");
  cmd->add_flag("--robust", args->robust, "Embree robust traversal mode");
  cmd->add_flag("-q,--quiet", args->quiet, "No progress bar or warnings");
  cmd->callback([args, &exitCode] { exitCode = runRender(*args); });
}

}  // namespace lucent::cli
