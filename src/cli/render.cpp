// lucent render SCENE.json [--method NAME] -o OUT.exr [--png OUT.png] [render options] [method options]
// The method's options come from its declaration (pipeline/options.h): their flags, parsing,
// validation, JSON echo, EXR metadata and help. Precedence: the method's defaults, then the scene
// file's render block (when it names this method), then the command line.
#include <filesystem>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cli/commands.h"
#include "cli/method_options.h"
#include "cli/progress.h"
#include "lucent/core/lane_clones.h"
#include "lucent/core/memory.h"
#include "lucent/core/parallel.h"
#include "lucent/methods/methods.h"
#include "lucent/scene/loader.h"

namespace lucent::cli {
namespace fs = std::filesystem;

namespace {

struct RenderArgs {
  std::string scene, method, output, png, resolution, isa;
  int threads = 0;
  uint64_t memoryLimit = 0;  // 0: the available memory
  bool quiet = false, robust = false, help = false;
  OptionValues methodOptions;  // as given, in order
};

// The render command's own options, beside the method's: name, value placeholder ("" for a
// flag), help.
struct RenderFlag {
  const char* names;
  const char* value;
  const char* help;
};
const RenderFlag kRenderFlags[] = {
    {"--method", "NAME", "rendering method (lucent methods lists them; default: the scene's render block's, else pt)"},
    {"-o, --output", "FILE", "output EXR file (required)"},
    {"--png", "FILE", "also write an sRGB PNG"},
    {"--threads", "N", "worker threads (0: all cores; default 0)"},
    {"--resolution", "WxH", "override the camera's resolution"},
    {"--memory-limit", "SIZE", "the most memory the render may hold, as 512M, 8G or bytes; one that would need more "
                               "stops at once, naming the option to lower (default: the available memory)"},
    {"--robust", "", "Embree's robust traversal (watertight at edges)"},
    {"--isa", "ISA", "run as a CPU of sse4.2, avx, avx2 or avx512 would: Embree's kernels and the lane loops "
                     "(default: this CPU's best)"},
    {"-q, --quiet", "", "no progress bar or warnings"},
    {"-h, --help", "", "this help, with the options of --method NAME"},
};

// Splits the arguments into the render command's own and the methods' (every method's options are
// known by name, so each can be told to take a value or not before the method is chosen).
RenderArgs parseArgs(const std::vector<std::string>& args) {
  RenderArgs a;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& arg = args[i];
    const size_t eq = arg.find('=');
    const bool inlineValue = arg.rfind("--", 0) == 0 && eq != std::string::npos;
    const std::string key = inlineValue ? arg.substr(0, eq) : arg;
    auto value = [&]() -> std::string {
      if (inlineValue) return arg.substr(eq + 1);
      if (i + 1 >= args.size()) throw std::invalid_argument(key + " needs a value");
      return args[++i];
    };
    if (key == "-h" || key == "--help") a.help = true;
    else if (key == "-q" || key == "--quiet") a.quiet = true;
    else if (key == "--robust") a.robust = true;
    else if (key == "-o" || key == "--output") a.output = value();
    else if (key == "--png") a.png = value();
    else if (key == "--method") a.method = value();
    else if (key == "--resolution") a.resolution = value();
    else if (key == "--isa") a.isa = value();
    else if (key == "--memory-limit") {
      const std::string text = value();
      try {
        a.memoryLimit = parseMemorySize(text);
      } catch (const std::invalid_argument& e) {
        throw std::invalid_argument("--memory-limit " + std::string(e.what()));
      }
      if (a.memoryLimit == 0) throw std::invalid_argument("--memory-limit must be more than 0 bytes");
    }
    else if (key == "--threads") {
      const std::string text = value();
      a.threads = int(parseOptionInteger("threads", text, 0, 4096));
    } else if (key.rfind("--", 0) == 0) {
      a.methodOptions.push_back(methodOptionArg(key, inlineValue ? std::optional(arg.substr(eq + 1)) : std::nullopt,
                                                [&] { return value(); }));
    } else if (key.rfind("-", 0) == 0 && key.size() > 1) {
      throw std::invalid_argument("unknown option " + key);
    } else if (a.scene.empty()) {
      a.scene = arg;
    } else {
      throw std::invalid_argument("one scene file only: '" + a.scene + "' and '" + arg + "'");
    }
  }
  return a;
}

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

// An output must not be one of the scene's inputs (an environment map, a texture).
void refuseToOverwrite(const std::vector<std::string>& inputs, const std::string& output, const std::string& flag) {
  std::error_code ec;
  const fs::path out = fs::weakly_canonical(output, ec);
  for (const std::string& input : inputs)
    if (out == fs::weakly_canonical(input, ec))
      throw std::invalid_argument(flag + " '" + output + "' is a file the scene is read from; choose another output");
}

void printHelp(const Method& method) {
  std::cout << "Usage: lucent render SCENE.json [--method NAME] -o OUT.exr [options]\n\nRender options:\n";
  for (const RenderFlag& f : kRenderFlags)
    std::cout << "  " << f.names << (*f.value ? std::string(" ") + f.value : "") << "\n      " << f.help << "\n";
  std::cout << "\nOptions of --method " << method.name() << " (" << method.summary() << "):\n"
            << methodOptionsHelp(method);
}

int runRender(const RenderArgs& a) {
  const Method* method = nullptr;
  Scene scene;
  Stopwatch total;
  RenderStats stats;
  if (!a.help || !a.scene.empty()) {
    if (a.scene.empty()) throw std::invalid_argument("no scene file given (lucent render SCENE.json -o OUT.exr)");
    if (a.output.empty() && !a.help) throw std::invalid_argument("no output file given (-o OUT.exr)");
    if (!a.help) {
      checkOutputPath(a.output, ".exr", "-o");
      if (!a.png.empty()) checkOutputPath(a.png, ".png", "--png");
      std::error_code ec;
      if (!a.png.empty() && fs::weakly_canonical(a.output, ec) == fs::weakly_canonical(a.png, ec))
        throw std::invalid_argument("-o and --png name the same file");
    }
    Stopwatch loadClock;
    scene = loadScene(a.scene, {a.quiet});
    stats.addStage("load_scene", loadClock.seconds());
    if (!a.help) {
      refuseToOverwrite(scene.inputFiles, a.output, "-o");
      if (!a.png.empty()) refuseToOverwrite(scene.inputFiles, a.png, "--png");
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
  // The scene's render block applies when it names this method (or none).
  OptionValues values;
  std::vector<std::string> origins;
  if (scene.render.present && (scene.render.method.empty() || scene.render.method == method->name()))
    for (const auto& [name, text] : scene.render.options) {
      origins.push_back(a.scene + ": render." + name);
      checkMethodOption(*method, name, origins.back());
      values.emplace_back(name, text);
    }
  for (const auto& [name, text] : a.methodOptions) {
    origins.push_back(flagOf(name));
    checkMethodOption(*method, name, flagOf(name));
    values.emplace_back(name, text);
  }
  const OptionValues resolved = resolveMethodOptions(*method, values, origins);

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

  RenderOutput out;
  {
    ProgressBar bar(!a.quiet);
    out = method->render(scene, visibility, resolved, [&](double f) { bar.update(f); });
  }
  for (const auto& s : out.stats.stageSeconds) stats.addStage(s.first, s.second);
  stats.counters = out.stats.counters;
  const double renderSeconds = total.seconds();

  const nlohmann::ordered_json options = methodOptionsJson(*method, resolved);
  nlohmann::ordered_json derived = nlohmann::ordered_json::object();
  for (const auto& [name, value] : out.stats.derived) derived[name] = value;
  std::string seed = "0";
  for (const auto& [name, text] : resolved)
    if (name == "seed") seed = text;
  ImageMetadata meta = {{"lucent:method", method->name()},
                        {"lucent:options", options.dump()},
                        {"lucent:derived", derived.dump()},
                        {"lucent:spp", std::to_string(out.sppDone)},
                        {"lucent:seed", seed},
                        {"lucent:render_seconds", std::to_string(renderSeconds)},
                        {"lucent:version", LUCENT_VERSION},
                        {"lucent:embree_version", Visibility::embreeVersion()},
                        {"lucent:embree_isa", visibility.isa()},
                        {"lucent:lane_isa", laneIsaName(laneIsa())},
                        {"lucent:scene", fs::absolute(a.scene).lexically_normal().string()},
                        {"lucent:scene_hash", hex(scene.contentHash)},
                        {"lucent:threads", std::to_string(parallel.threads())}};
  Stopwatch writeClock;
  writeExrAndPng(out.image, a.output, meta, a.png);
  stats.addStage("write_images", writeClock.seconds());

  nlohmann::ordered_json summary;
  summary["method"] = method->name();
  summary["options"] = options;
  summary["spp"] = out.sppDone;
  summary["threads"] = parallel.threads();
  summary["robust"] = a.robust;
  summary["embree_isa"] = visibility.isa();
  summary["lane_isa"] = laneIsaName(laneIsa());
  summary["memory_limit"] = memoryLimit();
  summary["seconds"] = total.seconds();
  for (const auto& [name, seconds] : stats.stageSeconds) summary["stages"][name] = seconds;
  for (const auto& [name, value] : stats.counters) summary["counters"][name] = value;
  summary["derived"] = derived;
  summary["output"] = a.output;
  if (!a.png.empty()) summary["png"] = a.png;
  summary["scene_hash"] = hex(scene.contentHash);
  std::cout << summary.dump() << std::endl;
  return 0;
}

}  // namespace

void addRenderCommand(CLI::App& app, int& exitCode) {
  CLI::App* cmd = app.add_subcommand("render", "Render a scene to an EXR (lucent render --method NAME --help)");
  // Every argument after `render` is this command's: its own options and the chosen method's,
  // which are known only once the method is (parseArgs).
  cmd->prefix_command();
  cmd->set_help_flag();
  cmd->callback([cmd, &exitCode] {
    RenderArgs args = parseArgs(cmd->remaining());
    exitCode = runRender(args);
  });
}

}  // namespace lucent::cli
