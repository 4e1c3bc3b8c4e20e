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
#include <sstream>
#include <string_view>
#include <tuple>

#include "cli/commands.h"
#include "cli/film_outputs.h"
#include "cli/method_options.h"
#include "cli/output_paths.h"
#include "cli/progress.h"
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

struct RenderArgs {
  std::string scene, method, output, png, isa, part;
  std::pair<int, int> resolution{0, 0};  // width, height; 0: the camera's
  PixelRect crop;                        // empty: the whole image
  std::pair<int, int> samples{0, 0};     // first, count; count 0: all
  int threads = 0;
  double checkpointSeconds = 0;
  bool resume = false;
  uint64_t memoryLimit = 0;  // 0: the available memory
  bool quiet = false, robust = false, help = false, logStages = false, strict = false;
  bool gltfHeightCorrelated = false;
  double lumensPerWatt = GltfOptions{}.lumensPerWatt;
  std::string gltfCamera;
  OptionValues methodOptions;  // as given, in order
};

// The value `parse` reads from a render flag's text; its OptionError named after the flag.
template <class Parse>
auto flagged(Parse parse) {
  try {
    return parse();
  } catch (const OptionError& e) {
    throw std::invalid_argument("--" + e.option() + ": " + e.what());
  }
}

// "X0,Y0,X1,Y1": integers with X0 < X1, Y0 < Y1 (inside the image: checked once its size is known).
PixelRect parseCrop(const std::string& text) {
  PixelRect r;
  char c1 = 0, c2 = 0, c3 = 0, rest = 0;
  std::istringstream in(text);
  if (!(in >> r.x0 >> c1 >> r.y0 >> c2 >> r.x1 >> c3 >> r.y1) || c1 != ',' || c2 != ',' || c3 != ',' || (in >> rest) ||
      r.x0 < 0 || r.y0 < 0 || r.x0 >= r.x1 || r.y0 >= r.y1)
    throw std::invalid_argument("--crop '" + text + "': expected X0,Y0,X1,Y1 with 0 <= X0 < X1 and 0 <= Y0 < Y1");
  return r;
}

// "FIRST:COUNT", FIRST >= 0, COUNT >= 1 (inside the samples per pixel: checked by the method).
std::pair<int, int> parseSamples(const std::string& text) {
  const size_t colon = text.find(':');
  if (colon == std::string::npos) throw std::invalid_argument("--samples '" + text + "': expected FIRST:COUNT");
  const int first = int(flagged([&] { return parseOptionInteger("samples", text.substr(0, colon), 0, 1 << 24); }));
  const int count = int(flagged([&] { return parseOptionInteger("samples", text.substr(colon + 1), 1, 1 << 24); }));
  return {first, count};
}

// --part rows:K/N or samples:K/N: the K-th of N equal parts of the image's rows (a crop of whole
// rows) or of each pixel's spp samples, set in `control`.
void applyPart(const std::string& text, const Scene& scene, int spp, RenderControl& control) {
  const size_t colon = text.find(':'), slash = text.find('/');
  const std::string axis = text.substr(0, colon);
  if (colon == std::string::npos || slash == std::string::npos || slash < colon || (axis != "rows" && axis != "samples"))
    throw std::invalid_argument("--part '" + text + "': expected rows:K/N or samples:K/N");
  const int count = int(flagged([&] { return parseOptionInteger("part", text.substr(slash + 1), 1, 1 << 24); }));
  const int index = int(flagged([&] { return parseOptionInteger("part", text.substr(colon + 1, slash - colon - 1), 0, count - 1); }));
  if (!control.crop.empty() || control.firstSample != 0 || control.sampleCount != 0)
    throw std::invalid_argument("--part: give either --part or --crop and --samples");
  const int total = axis == "rows" ? scene.camera.height : spp;
  if (count > total)
    throw std::invalid_argument("--part " + text + ": " + std::to_string(count) + " parts of " + std::to_string(total) +
                                (axis == "rows" ? " rows" : " samples per pixel (--spp)"));
  const int first = int(int64_t(index) * total / count), end = int(int64_t(index + 1) * total / count);
  if (axis == "rows") control.crop = {0, first, scene.camera.width, end};
  else control.firstSample = first, control.sampleCount = end - first;
}

// "WIDTHxHEIGHT", each in [1, kMaxImageSide], at most kMaxImagePixels in all.
std::pair<int, int> parseResolution(const std::string& text) {
  int w = 0, h = 0;
  char x = 0, rest = 0;
  std::istringstream in(text);
  if (!(in >> w >> x >> h) || x != 'x' || (in >> rest) || w < 1 || h < 1 || w > kMaxImageSide || h > kMaxImageSide)
    throw std::invalid_argument("--resolution '" + text + "': expected WIDTHxHEIGHT, e.g. 512x512");
  if (uint64_t(w) * h > kMaxImagePixels) throw std::invalid_argument("--resolution '" + text + "': more than 2^26 pixels");
  return {w, h};
}

// "512M", "8G" or bytes: more than 0, within what the process may address.
uint64_t parseMemoryLimit(const std::string& text) {
  uint64_t limit = 0;
  try {
    limit = parseMemorySize(text);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("--memory-limit " + std::string(e.what()));
  }
  if (limit == 0) throw std::invalid_argument("--memory-limit must be more than 0 bytes");
  if (limit > addressSpaceLimit())
    throw std::invalid_argument("--memory-limit " + text + ": more than this process may address (ulimit -v: " +
                                memoryText(addressSpaceLimit()) + ")");
  return limit;
}

std::string pairText(const std::pair<int, int>& p, char separator) {
  return p.second == 0 ? std::string() : std::to_string(p.first) + separator + std::to_string(p.second);
}

// The render command's own options, beside the method's, declared as the methods' are
// (pipeline/options.h): the help and the parsing read this table.
const OptionTable<RenderArgs>& renderFlags() {
  static const OptionTable<RenderArgs> table = [] {
    using A = RenderArgs;
    OptionTable<A> t;
    t.text("method", &A::method, "", "rendering method (lucent methods lists them); none: the scene's render block's, else pt");
    t.placeholder("method", "NAME");
    t.text("output", &A::output, "", "output EXR file (required)");
    t.placeholder("output", "FILE").shortFlag("output", "-o");
    t.text("png", &A::png, "", "also write an sRGB PNG");
    t.placeholder("png", "FILE");
    t.integer("threads", &A::threads, 0, kMaxThreads, "threads", "worker threads (0: all cores)");
    t.value<std::pair<int, int>>("resolution", &A::resolution, "WxH", parseResolution,
                                 [](const std::pair<int, int>& r) { return pairText(r, 'x'); },
                                 "override the camera's resolution");
    t.value<PixelRect>("crop", &A::crop, "X0,Y0,X1,Y1", parseCrop,
                       [](const PixelRect& r) {
                         return r.empty() ? std::string()
                                          : std::to_string(r.x0) + "," + std::to_string(r.y0) + "," +
                                                std::to_string(r.x1) + "," + std::to_string(r.y1);
                       },
                       "render only the pixels [X0, X1) x [Y0, Y1): a part of a split render, with OUT.film for "
                       "lucent merge");
    t.value<std::pair<int, int>>("samples", &A::samples, "FIRST:COUNT", parseSamples,
                                 [](const std::pair<int, int>& s) { return pairText(s, ':'); },
                                 "take only the camera samples FIRST to FIRST+COUNT-1 of each pixel: a part of a "
                                 "split render, with OUT.film for lucent merge");
    t.text("part", &A::part, "",
           "the K-th of N parts (K from 0) of the image's rows or of each pixel's samples, as --crop or --samples "
           "would give it (for job arrays)");
    t.placeholder("part", "rows|samples:K/N");
    t.real("checkpoint", &A::checkpointSeconds, 1e-3, 1e9, "s",
           "every SECONDS, write the render's state to OUT.film (also on SIGINT and SIGTERM)");
    t.placeholder("checkpoint", "SECONDS");
    t.flag("resume", &A::resume, "continue from OUT.film, left by a checkpoint or a stop, if there is one");
    t.value<uint64_t>("memory_limit", &A::memoryLimit, "SIZE", parseMemoryLimit,
                      [](const uint64_t& bytes) { return bytes == 0 ? std::string() : memoryText(bytes); },
                      "the most memory the render may hold, as 512M, 8G or bytes; one that would need more stops "
                      "at once, naming the option to lower (none: the available memory)");
    t.flag("robust", &A::robust, "Embree's robust traversal (watertight at edges)");
    t.text("isa", &A::isa, "",
           "run as a CPU of sse4.2, avx, avx2 or avx512 would: Embree's kernels and the lane loops (none: this "
           "CPU's best)");
    t.placeholder("isa", "ISA");
    t.flag("strict", &A::strict,
           "refuse a scene whose files hold what the render would leave out (a glTF material's normal texture: "
           "the JSON line's \"ignored\")");
    t.choice<bool>("gltf_masking", &A::gltfHeightCorrelated, {{"separable", false}, {"height-correlated", true}},
                   "Smith masking-shadowing of glTF materials: Appendix B's separable form, or the height-correlated "
                   "one of the Khronos sample renderer and many GPU engines (a scene file's glTF entry may set its "
                   "own)");
    t.real("lumens_per_watt", &A::lumensPerWatt, 1e-6, 1e6, "lm/W",
           "glTF lights' photometric intensities (cd, lx) to watts (a scene file's glTF entry may set its own)");
    t.text("gltf_camera", &A::gltfCamera, "",
           "render a glTF file from the camera of this name (its node's or its own; none: the first)");
    t.placeholder("gltf_camera", "NAME");
    t.flag("quiet", &A::quiet, "no progress bar or warnings");
    t.shortFlag("quiet", "-q");
    t.flag("log_stages", &A::logStages, "print each stage's name on stderr as it starts, with the seconds since the start");
    t.flag("help", &A::help, "this help, with the options of --method NAME");
    t.shortFlag("help", "-h");
    return t;
  }();
  return table;
}

// The render flag whose long or short form is `key`, or nullptr.
const OptionSpec* renderFlag(const std::string& key) {
  for (const OptionSpec& spec : renderFlags().specs())
    if (key == spec.flag() || key == spec.shortFlag) return &spec;
  return nullptr;
}

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
    if (const OptionSpec* flag = renderFlag(key)) {
      const bool takesValue = flag->kind != OptionKind::Flag;
      if (!takesValue && inlineValue) throw std::invalid_argument(key + " takes no value");
      try {
        renderFlags().set(a, flag->name, takesValue ? value() : "true");
      } catch (const OptionError& e) {
        throw std::invalid_argument(flag->flag() + ": " + e.what());
      }
    } else if (key.rfind("--", 0) == 0) {
      a.methodOptions.push_back(methodOptionArg(key, inlineValue ? std::optional(arg.substr(eq + 1)) : std::nullopt,
                                                i + 1 < args.size() ? std::optional(args[i + 1]) : std::nullopt,
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
  // The scene's render block applies when it names this method (or none).
  std::vector<std::string> origins;
  OptionValues values = sceneRenderBlockOptions(scene, *method, origins);
  for (const auto& [name, text] : a.methodOptions) {
    origins.push_back(flagOf(name));
    checkMethodOption(*method, name, flagOf(name));
    values.emplace_back(name, text);
  }
  const std::unique_ptr<MethodOptions> resolved = resolveMethodOptions(*method, values, origins);
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
  info.sceneHash = hex(scene.contentHash);
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
  summary["scene_hash"] = hex(scene.contentHash);
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
    RenderArgs args = parseArgs(cmd->remaining());
    exitCode = runRender(args);
  });
}

}  // namespace lucent::cli
