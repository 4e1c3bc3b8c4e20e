// lucent render SCENE.json [--method NAME] -o OUT.exr [--png OUT.png] [render options] [method options]
// The method's options come from its declaration (pipeline/options.h): their flags, parsing,
// validation, JSON echo, EXR metadata and help. Precedence: the method's defaults, then the scene
// file's render block (when it names this method), then the command line.
#include <signal.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <optional>
#include <nlohmann/json.hpp>
#include <string_view>
#include <tuple>

#include "cli/commands.h"
#include "cli/film_outputs.h"
#include "cli/method_options.h"
#include "cli/output_paths.h"
#include "cli/progress.h"
#include "cli/render_args.h"
#include "core/json_text.h"
#include "lucent/core/lane_clones.h"
#include "lucent/core/memory.h"
#include "lucent/core/parallel.h"
#include "lucent/methods/methods.h"
#include "lucent/pipeline/film_file.h"
#include "lucent/pipeline/render_stages.h"
#include "lucent/scene/loader.h"

namespace lucent::cli {
namespace fs = std::filesystem;

namespace {

// While alive: SIGINT and SIGTERM ask the render to stop; a second one ends the process as usual.
// Once it is gone (the render returned, its outputs written) the process ignores both until it
// exits: the render is done, and a signal in the process's teardown would otherwise report a
// finished render as killed.
class StopOnSignals {
 public:
  StopOnSignals() {
    requested_ = false;
    signal_ = 0;
    struct sigaction action {};
    action.sa_handler = &StopOnSignals::handle;
    action.sa_flags = SA_RESETHAND;
    sigemptyset(&action.sa_mask);
    sigaction(SIGINT, &action, nullptr);
    sigaction(SIGTERM, &action, nullptr);
  }
  ~StopOnSignals() {
    struct sigaction ignore {};
    ignore.sa_handler = SIG_IGN;
    sigemptyset(&ignore.sa_mask);
    sigaction(SIGINT, &ignore, nullptr);
    sigaction(SIGTERM, &ignore, nullptr);
  }
  StopOnSignals(const StopOnSignals&) = delete;
  StopOnSignals& operator=(const StopOnSignals&) = delete;
  const std::atomic<bool>& requested() const { return requested_; }
  int signal() const { return signal_; }

 private:
  static void handle(int signal) {
    signal_ = signal;
    requested_ = true;
  }
  static inline std::atomic<bool> requested_{false};
  static inline std::atomic<int> signal_{0};
};

void printHelp(const Method& method) {
  std::cout << "Usage: lucent render SCENE.json [--method NAME] -o OUT.exr [options]\n\nRender options:\n";
  std::cout << optionsHelp(renderFlags().specs()) << "\nOptions of --method " << method.name() << " ("
            << method.summary() << "):\n"
            << optionsHelp(method.options());
}

int runRender(const RenderArgs& a) {
  const Method* method = nullptr;
  Scene scene;
  Stopwatch total;
  RenderStats stats;
  struct ObserverScope {  // the observer refers to `total`: it ends with this render
    ~ObserverScope() { setStageObserver(nullptr); }
  } observerScope;
  if (a.logStages)
    setStageObserver([&total](const std::string& stage) {
      std::fprintf(stderr, "lucent: stage %s at %.3f s\n", stage.c_str(), total.seconds());
      std::fflush(stderr);
    });
  if (!a.help || !a.scene.empty()) {
    if (a.scene.empty()) throw std::invalid_argument("no scene file given (lucent render SCENE.json -o OUT.exr)");
    if (a.output.empty() && !a.help) throw std::invalid_argument("no output file given (-o OUT.exr)");
    if (!a.help) {
      std::error_code ec;
      if (!a.png.empty() && fs::weakly_canonical(a.output, ec) == fs::weakly_canonical(a.png, ec))
        throw std::invalid_argument("-o and --png name the same file");
    }
    Stopwatch loadClock;
    setMemoryLimit(a.memoryLimit);  // the scene's images are checked against it too
    scene = loadScene(a.scene, {a.quiet, {a.gltfHeightCorrelated, a.lumensPerWatt, a.gltfCamera}});
    stats.addStage("load_scene", loadClock.seconds());
    if (a.strict && !scene.ignored.empty()) {
      std::string list;
      for (const std::string& left : scene.ignored) list += "\n  " + left;
      throw std::invalid_argument("--strict: the render would leave out what the scene's files hold:" + list);
    }
    if (!a.help) {
      checkOutputFile(a.output, ".exr", "-o", scene.inputFiles);
      if (!a.png.empty()) checkOutputFile(a.png, ".png", "--png", scene.inputFiles);
      checkOutputFile(filmPathFor(a.output), ".film", "-o (its film file)", scene.inputFiles);
    }
  }
  const std::string methodName = !a.method.empty()       ? a.method
                                 : !scene.render.method.empty() ? scene.render.method
                                                                 : "pt";
  method = &renderingMethod(methodName);
  if (a.help) {
    printHelp(*method);
    return 0;
  }
  const std::unique_ptr<MethodOptions> resolved = renderMethodOptions(a, scene, *method);
  checkOutputDirectories(*method, resolved->values(), scene);

  if (a.resolution.second > 0) {
    scene.camera.width = a.resolution.first;
    scene.camera.height = a.resolution.second;
    scene.contentHash = sceneContentHash(scene);
  }

  // Embree's kernels and the lane loops of the instruction set asked for (SSE 4.2 and AVX have
  // the baseline lane loops).
  if (!a.isa.empty() && a.isa != "sse4.2" && a.isa != "avx" && a.isa != "avx2" && a.isa != "avx512")
    throw std::invalid_argument("--isa '" + a.isa + "': expected sse4.2, avx, avx2 or avx512");
  if (!a.isa.empty()) {
    const std::vector<std::string> runs = supportedEmbreeIsas();
    if (std::find(runs.begin(), runs.end(), a.isa) == runs.end()) {
      std::string list;
      for (const std::string& isa : runs) list += (list.empty() ? "" : ", ") + isa;
      throw std::invalid_argument("--isa " + a.isa + ": this CPU does not run it (it runs " + list + ")");
    }
  }
  if (!a.isa.empty())
    setLaneIsa(a.isa == "avx512" ? LaneIsa::Avx512 : a.isa == "avx2" ? LaneIsa::Avx2 : LaneIsa::Baseline);
  ParallelScope parallel(a.threads);
  setMemoryLimit(a.memoryLimit);
  Stopwatch bvhClock;
  VisibilityOptions visOptions;
  visOptions.robust = a.robust;
  visOptions.isa = a.isa;
  const Visibility visibility(scene, visOptions);
  stats.addStage("build_bvh", bvhClock.seconds());

  // The part, the film file, and what it would be a film of.
  RenderControl control;
  const int spp = resolved->common().spp;
  control.crop = a.crop;
  std::tie(control.firstSample, control.sampleCount) = a.samples;
  if (!a.part.empty()) applyPart(a.part, scene, spp, control);
  const RenderPart part = resolvePart(control, scene, spp);
  const nlohmann::ordered_json options = methodOptionsJson(*method, resolved->values());
  FilmFileInfo info;
  info.method = method->name();
  info.options = jsonText(options);
  info.scene = fs::absolute(a.scene).lexically_normal().string();
  info.sceneHash = contentHashText(scene);
  info.version = LUCENT_VERSION;
  info.embreeIsa = visibility.isa();
  info.laneIsa = laneIsaName(laneIsa());
  info.spp = spp;
  info.firstSample = part.sampleBegin;
  info.sampleCount = part.samples();
  const std::string filmPath = filmPathFor(a.output);
  if ((control.checkpointSeconds = a.checkpointSeconds) > 0 || a.resume) {
    if (!method->interruptible())
      throw std::invalid_argument(std::string(a.resume ? "--resume" : "--checkpoint") + ": --method " + method->name() +
                                  " cannot be checkpointed or resumed; render it in parts (--crop, --samples) instead");
  }
  std::optional<FilmFile> resumed;
  if (a.resume && fs::exists(filmPath)) {
    resumed = readFilmFile(filmPath);
    std::string difference = renderDifference(resumed->info, info);
    if (difference.empty() && !(resumed->film->region() == part.region)) difference = "it is of another --crop";
    if (difference.empty() && (resumed->info.firstSample != info.firstSample || resumed->info.sampleCount != info.sampleCount))
      difference = "it is of --samples " + std::to_string(resumed->info.firstSample) + ":" +
                   std::to_string(resumed->info.sampleCount);
    if (!difference.empty())
      throw std::invalid_argument("--resume: '" + filmPath + "' is not a film of this render: " + difference);
    control.resume = resumed->film.get();
  }
  bool checkpointed = false;
  control.checkpoint = [&](const Film& film) {
    writeFilmFile(filmPath, film, info);
    checkpointed = true;
  };

  RenderOutput out;
  int stopSignal = 0;
  // From here to the end, SIGINT and SIGTERM ask the render to stop (the scene's loading and the
  // BVH before it end at once by the signal's default action); one that comes after the render
  // returned lets the outputs be written whole, and is otherwise ignored: the render is done.
  StopOnSignals signals;
  {
    ProgressBar bar(!a.quiet);
    control.progress = [&](double f) { bar.update(f); };
    control.stop = &signals.requested();
    try {
      out = method->render(scene, visibility, *resolved, control);
    } catch (const RenderStopped&) {
      // Before any sample (or a method that cannot keep a part of its image): nothing is written,
      // and a checkpoint resumed from stays as it was.
      const int signal = signals.signal() > 0 ? signals.signal() : SIGTERM;
      std::cerr << "lucent: stopped by " << (signal == SIGINT ? "SIGINT" : "SIGTERM")
                << " before the image had any sample to keep; nothing written\n";
      return 128 + signal;
    }
    if (!out.complete) stopSignal = signals.signal();
  }
  for (const auto& s : out.stats.stageSeconds) stats.addStage(s.first, s.second);
  stats.counters = out.stats.counters;

  nlohmann::ordered_json derived = nlohmann::ordered_json::object();
  for (const auto& [name, value] : out.stats.derived) derived[name] = value;
  info.derived = jsonText(derived);
  info.complete = out.complete;
  info.counters = out.stats.counters;
  ImageMetadata meta = filmMetadata(info, *out.film);
  meta.emplace_back("lucent:render_seconds", std::to_string(total.seconds()));
  meta.emplace_back("lucent:threads", std::to_string(parallel.threads()));
  // Whole numbers (samples) as integers.
  auto measuredJson = [](double value) {
    return value == std::floor(value) && std::abs(value) < 0x1p53 ? nlohmann::json(int64_t(value)) : nlohmann::json(value);
  };
  for (const auto& [name, value] : out.measured) meta.emplace_back("lucent:" + name, measuredJson(value).dump());
  // What the scene's files hold that this render leaves out: a reference says how it differs.
  if (!scene.ignored.empty()) meta.emplace_back("lucent:ignored", nlohmann::json(scene.ignored).dump());
  // A part of a split render and an interrupted render keep their film (merged later, or resumed);
  // a whole render that completes removes the checkpoint it resumed from or wrote.
  std::vector<FileToWrite> alsoWrite;
  const bool keepFilm = control.isPart() || !out.complete;
  if (keepFilm) alsoWrite.push_back(filmFile(filmPath, *out.film, info));
  Stopwatch writeClock;
  writeExrAndPng(out.image, a.output, meta, a.png, std::move(alsoWrite));
  if (!keepFilm && (checkpointed || resumed)) fs::remove(filmPath);
  stats.addStage("write_images", writeClock.seconds());

  nlohmann::ordered_json summary;
  summary["method"] = method->name();
  summary["options"] = options;
  summary["spp"] = out.sppDone;
  summary["complete"] = out.complete;
  if (!out.complete) summary["stopped_by"] = stopSignal == SIGINT ? "SIGINT" : stopSignal == SIGTERM ? "SIGTERM" : "stop";
  if (control.isPart()) {
    const PixelRect& r = part.region;
    summary["crop"] = {r.x0, r.y0, r.x1, r.y1};
    summary["samples"] = {part.sampleBegin, part.samples()};
  }
  if (resumed) {
    uint64_t samples = 0;
    for (uint32_t taken : resumed->film->samplesTaken()) samples += taken;
    summary["resumed_samples"] = samples;
  }
  summary["threads"] = parallel.threads();
  summary["robust"] = a.robust;
  summary["embree_isa"] = visibility.isa();
  summary["lane_isa"] = laneIsaName(laneIsa());
  summary["memory_limit"] = memoryLimit();
  summary["seconds"] = total.seconds();
  for (const auto& [name, seconds] : stats.stageSeconds) summary["stages"][name] = seconds;
  for (const auto& [name, value] : stats.counters) summary["counters"][name] = value;
  summary["derived"] = derived;
  for (const auto& [name, value] : out.measured) summary[name] = measuredJson(value);
  summary["output"] = a.output;
  if (!a.png.empty()) summary["png"] = a.png;
  if (keepFilm) summary["film"] = filmPath;
  summary["scene_hash"] = contentHashText(scene);
  if (!scene.ignored.empty()) summary["ignored"] = scene.ignored;
  std::cout << jsonText(summary) << std::endl;
  // Interrupted: the status a shell gives a process that the signal ended.
  return out.complete ? 0 : 128 + (stopSignal > 0 ? stopSignal : SIGTERM);
}

}  // namespace

void addRenderCommand(CLI::App& app, int& exitCode) {
  CLI::App* cmd = app.add_subcommand("render", "Render a scene to an EXR (lucent render --method NAME --help)");
  // Every argument after `render` is this command's: its own options and the chosen method's,
  // which are known only once the method is (parseArgs).
  cmd->prefix_command();
  cmd->set_help_flag();
  cmd->callback([cmd, &exitCode] {
    RenderArgs args = parseRenderArgs(cmd->remaining());
    exitCode = runRender(args);
  });
}

}  // namespace lucent::cli
