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
#include "cli/method_options.h"
#include "cli/progress.h"
#include "cli/render_args.h"
#include "lucent/core/stats.h"
#include "lucent/core/stop.h"
#include "lucent/methods/methods.h"
#include "lucent/render/render_session.h"

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
  Stopwatch total;
  struct ObserverScope {  // the observer refers to `total`: it ends with this render
    ~ObserverScope() { setStageObserver(nullptr); }
  } observerScope;
  if (a.logStages)
    setStageObserver([&total](const std::string& stage) {
      std::fprintf(stderr, "lucent: stage %s at %.3f s\n", stage.c_str(), total.seconds());
      std::fflush(stderr);
    });
  if (a.help && a.scene.empty()) {
    printHelp(renderingMethod(a.method.empty() ? "pt" : a.method));
    return 0;
  }
  if (a.scene.empty()) throw std::invalid_argument("no scene file given (lucent render SCENE.json -o OUT.exr)");
  if (a.output.empty() && !a.help) throw std::invalid_argument("no output file given (-o OUT.exr)");
  SceneSettings settings;
  settings.load = {a.quiet, {a.gltfHeightCorrelated, a.gltfBendNormalMaps, a.lumensPerWatt, a.gltfCamera}};
  if (a.resolution.second > 0) settings.resolution = a.resolution;
  settings.strict = a.strict;
  settings.isa = a.isa;
  settings.robust = a.robust;
  settings.memoryLimit = a.memoryLimit;
  OpenScene scene(a.scene, settings);
  if (a.help) {
    printHelp(renderingMethod(!a.method.empty() ? a.method : !scene.scene().render.method.empty() ? scene.scene().render.method : "pt"));
    return 0;
  }
  RenderRequest request;
  request.method = a.method;
  request.options = a.methodOptions;
  request.optionName = flagOf;
  request.output = a.output;
  request.png = a.png;
  request.crop = a.crop;
  request.samples = a.samples;
  request.part = a.part;
  request.checkpointSeconds = a.checkpointSeconds;
  request.resume = a.resume;
  request.threads = a.threads;
  RenderSession rendering(scene, request);

  // From here to the end, SIGINT and SIGTERM ask the render to stop (the scene's loading and the
  // BVH before it end at once by the signal's default action); one that comes after the render
  // returned lets the outputs be written whole, and is otherwise ignored: the render is done.
  StopOnSignals signals;
  auto signalName = [&] { return signals.signal() == SIGINT ? "SIGINT" : "SIGTERM"; };
  RenderResult result;
  {
    ProgressBar bar(!a.quiet);
    RenderHooks hooks;
    hooks.progress = [&](double f) { bar.update(f); };
    hooks.stop = &signals.requested();
    hooks.stoppedBy = [&] { return std::string(signals.signal() > 0 ? signalName() : "stop"); };
    try {
      result = rendering.run(hooks);
    } catch (const RenderStopped&) {
      // Before any sample (or a method that cannot keep a part of its image): nothing is written,
      // and a checkpoint resumed from stays as it was.
      std::cerr << "lucent: stopped by " << signalName() << " before the image had any sample to keep; nothing written\n";
      return 128 + (signals.signal() > 0 ? signals.signal() : SIGTERM);
    }
  }
  std::cout << result.summary << std::endl;
  // Interrupted: the status a shell gives a process that the signal ended.
  return result.render.complete ? 0 : 128 + (signals.signal() > 0 ? signals.signal() : SIGTERM);
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
