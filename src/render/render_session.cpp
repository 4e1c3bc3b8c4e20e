#include "lucent/render/render_session.h"

#include <algorithm>
#include <numeric>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <tuple>

#include "core/json_text.h"
#include "lucent/core/lane_clones.h"
#include "lucent/core/memory.h"
#include "lucent/core/parallel.h"
#include "lucent/image/image.h"
#include "lucent/methods/methods.h"
#include "lucent/pipeline/film_file.h"
#include "lucent/pipeline/render_stages.h"
#include "render/film_outputs.h"
#include "render/output_paths.h"

namespace lucent {
namespace fs = std::filesystem;

namespace {

void checkIsa(const std::string& isa) {
  if (isa.empty()) return;
  if (std::find(std::begin(kEmbreeIsas), std::end(kEmbreeIsas), isa) == std::end(kEmbreeIsas))
    throw std::invalid_argument("--isa '" + isa + "': expected sse4.2, avx, avx2 or avx512");
  const std::vector<std::string> runs = supportedEmbreeIsas();
  if (std::find(runs.begin(), runs.end(), isa) == runs.end()) {
    std::string list;
    for (const std::string& supported : runs) list += (list.empty() ? "" : ", ") + supported;
    throw std::invalid_argument("--isa " + isa + ": this CPU does not run it (it runs " + list + ")");
  }
}

// The lane loops of the instruction set asked for (SSE 4.2 and AVX have the baseline loops), else
// the best this CPU runs.
LaneIsa laneIsaFor(const std::string& isa) {
  if (isa.empty()) return supportedLaneIsas().back();
  return isa == "avx512" ? LaneIsa::Avx512 : isa == "avx2" ? LaneIsa::Avx2 : LaneIsa::Baseline;
}

// --part rows:K/N or samples:K/N: the K-th of N equal parts of the image's rows (a crop of whole
// rows) or of each pixel's spp samples, set in `control`.
void applyPart(const std::string& text, const Scene& scene, int spp, RenderControl& control) {
  const size_t colon = text.find(':'), slash = text.find('/');
  const std::string axis = text.substr(0, colon);
  if (colon == std::string::npos || slash == std::string::npos || slash < colon || (axis != "rows" && axis != "samples"))
    throw std::invalid_argument("--part '" + text + "': expected rows:K/N or samples:K/N");
  auto number = [&](const std::string& digits, int64_t min, int64_t max) {
    try {
      return int(parseOptionInteger("part", digits, min, max));
    } catch (const OptionError& e) {
      throw std::invalid_argument(std::string("--part: ") + e.what());
    }
  };
  const int count = number(text.substr(slash + 1), 1, 1 << 24);
  const int index = number(text.substr(colon + 1, slash - colon - 1), 0, count - 1);
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

// Whole numbers (samples) as integers.
nlohmann::json measuredJson(double value) {
  return value == std::floor(value) && std::abs(value) < 0x1p53 ? nlohmann::json(int64_t(value)) : nlohmann::json(value);
}

}  // namespace

namespace {

void checkSceneSettings(const SceneSettings& settings) {
  const auto [width, height] = settings.resolution.value_or(std::pair<int, int>{1, 1});
  if (width < 1 || height < 1 || width > kMaxImageSide || height > kMaxImageSide ||
      uint64_t(width) * uint64_t(height) > kMaxImagePixels)
    throw std::invalid_argument("resolution " + std::to_string(width) + "x" + std::to_string(height) +
                                ": each side from 1 to " + std::to_string(kMaxImageSide) + ", at most 2^26 pixels");
  checkIsa(settings.isa);
}

}  // namespace

OpenScene::OpenScene(const std::string& path, const SceneSettings& settings) : path_(path), settings_(settings) {
  checkSceneSettings(settings);
  // Before the clock: loading the image writer is the process's set-up, not the scene's loading;
  // so is loading the texture reader, which the first texture does: left out of the stage.
  loadImageWriter();
  const double loadingBefore = codecLoadingSeconds();
  Stopwatch clock;
  setMemoryLimit(settings.memoryLimit);  // the scene's images are checked against it too
  scene_ = loadScene(path, settings.load);
  const double codecs = codecLoadingSeconds() - loadingBefore;
  stats_.addStage("load_scene", clock.seconds() - codecs);
  prepare();
}

OpenScene::OpenScene(Scene scene, const std::string& path, const SceneSettings& settings)
    : path_(path), settings_(settings), scene_(std::move(scene)) {
  checkSceneSettings(settings);
  stats_.addStage("load_scene", 0);
  prepare();
}

void OpenScene::prepare() {
  if (settings_.strict && !scene_.ignored.empty()) {
    std::string list;
    for (const std::string& left : scene_.ignored) list += "\n  " + left;
    throw std::invalid_argument("--strict: the render would leave out what the scene's files hold:" + list);
  }
  if (settings_.resolution) {
    std::tie(scene_.camera.width, scene_.camera.height) = *settings_.resolution;
    scene_.contentHash = sceneContentHash(scene_);
  }
}

const Visibility& OpenScene::visibility() {
  if (!visibility_) {
    Stopwatch clock;
    VisibilityOptions options;
    options.robust = settings_.robust;
    options.isa = settings_.isa;
    visibility_ = std::make_unique<Visibility>(scene_, options);
    stats_.addStage("build_bvh", clock.seconds());
  }
  return *visibility_;
}

RenderSession::RenderSession(OpenScene& scene, RenderRequest request) : scene_(scene), request_(std::move(request)) {
  const Scene& s = scene.scene();
  const RenderRequest& r = request_;
  auto name = [&](const std::string& option) { return r.optionName ? r.optionName(option) : "--" + option; };
  if (r.threads < 0 || r.threads > kMaxThreads)
    throw std::invalid_argument("threads " + std::to_string(r.threads) + ": expected 0 (all cores) to " +
                                std::to_string(kMaxThreads));
  if (!r.png.empty() && r.output.empty()) throw std::invalid_argument("a PNG is written beside the EXR: give both");
  if (!r.output.empty()) {
    std::error_code ec;
    if (!r.png.empty() && fs::weakly_canonical(r.output, ec) == fs::weakly_canonical(r.png, ec))
      throw std::invalid_argument("-o and --png name the same file");
    checkOutputFile(r.output, ".exr", "-o", s.inputFiles);
    if (!r.png.empty()) checkOutputFile(r.png, ".png", "--png", s.inputFiles);
    checkOutputFile(filmPathFor(r.output), ".film", "-o (its film file)", s.inputFiles);
  }
  method_ = &renderingMethod(!r.method.empty() ? r.method : !s.render.method.empty() ? s.render.method : "pt");

  // The method's defaults, then the scene file's render block, then the front end's values.
  std::vector<std::string> origins;
  OptionValues values = sceneRenderBlockOptions(s, *method_, origins);
  for (const auto& [option, text] : r.options) {
    origins.push_back(name(option));
    checkMethodOption(*method_, option, origins.back());
    values.emplace_back(option, text);
  }
  try {
    options_ = method_->resolve(values);
  } catch (const OptionError& e) {
    // Named after the last value given for the option (the front end's over the scene's).
    for (size_t i = values.size(); i-- > 0;)
      if (values[i].first == e.option()) throw OptionError(e.option(), origins[i] + ": " + e.what());
    throw OptionError(e.option(), name(e.option()) + ": " + e.what());
  }
  checkOutputDirectories(*method_, options_->values(), s);
  if (!r.output.empty()) loadImageWriter();  // loaded already where OpenScene read the scene's file
  ignored_ = s.ignored;
  for (size_t i = 0; i < s.materials.size(); ++i)
    if (s.materials[i].transmission > 0 && method_->rendersTransmission() == TransmissionRendered::InPart)
      ignored_.push_back("material '" + s.materialNames[i] +
                         "': the light its KHR_materials_transmission passes through the surface, in part (--method " +
                         method_->name() + "; pt renders it)");
  if (scene_.settings().strict && ignored_.size() > s.ignored.size()) {
    std::string list;
    for (size_t i = s.ignored.size(); i < ignored_.size(); ++i) list += "\n  " + ignored_[i];
    throw std::invalid_argument("--strict: the render would leave out what the scene's files hold:" + list);
  }

  if ((r.checkpointSeconds > 0 || r.resume) && !method_->interruptible())
    throw std::invalid_argument(std::string(r.resume ? "--resume" : "--checkpoint") + ": --method " + method_->name() +
                                " cannot be checkpointed or resumed; render it in parts (--crop, --samples) instead");
  if ((r.checkpointSeconds > 0 || r.resume) && r.output.empty())
    throw std::invalid_argument(std::string(r.resume ? "--resume" : "--checkpoint") +
                                ": the film is kept beside the output; give the output (-o)");
  control_.crop = r.crop;
  std::tie(control_.firstSample, control_.sampleCount) = r.samples;
  if (!r.part.empty()) applyPart(r.part, s, options_->common().spp, control_);
  resolvePart(control_, s, options_->common().spp);  // throws for a part outside the image or the samples
}

RenderSession::~RenderSession() = default;

namespace {

// The film of an earlier run of this render and part, to go on from; throws if it is another's.
std::optional<FilmFile> filmToResume(const std::string& path, const FilmFileInfo& info, const RenderPart& part) {
  if (!fs::exists(path)) return std::nullopt;
  FilmFile resumed = readFilmFile(path);
  std::string difference = renderDifference(resumed.info, info);
  if (difference.empty() && !(resumed.film->region() == part.region)) difference = "it is of another --crop";
  if (difference.empty() && (resumed.info.firstSample != info.firstSample || resumed.info.sampleCount != info.sampleCount))
    difference = "it is of --samples " + std::to_string(resumed.info.firstSample) + ":" +
                 std::to_string(resumed.info.sampleCount);
  if (!difference.empty())
    throw std::invalid_argument("--resume: '" + path + "' is not a film of this render: " + difference);
  return resumed;
}

// The EXR's header: how the render was made (filmMetadata), its time and threads, what it measured,
// and what the scene's files hold that it leaves out, so that a reference says how it differs.
ImageMetadata imageMetadata(const FilmFileInfo& info, const RenderOutput& out, const std::vector<std::string>& ignored,
                            double seconds, int threads) {
  ImageMetadata meta = filmMetadata(info, *out.film);
  meta.emplace_back("lucent:render_seconds", std::to_string(seconds));
  meta.emplace_back("lucent:threads", std::to_string(threads));
  for (const auto& [key, value] : out.measured) meta.emplace_back("lucent:" + key, measuredJson(value).dump());
  if (!ignored.empty()) meta.emplace_back("lucent:ignored", nlohmann::json(ignored).dump());
  return meta;
}

}  // namespace

FilmFileInfo RenderSession::filmInfo(const Visibility& visibility, const RenderPart& part) const {
  FilmFileInfo info;
  info.method = method_->name();
  info.options = optionsJsonText(method_->options(), options_->values());
  info.scene = fs::absolute(scene_.path()).lexically_normal().string();
  info.sceneHash = contentHashText(scene_.scene());
  info.version = LUCENT_VERSION;
  info.embreeIsa = visibility.isa();
  info.laneIsa = laneIsaName(laneIsa());
  info.spp = options_->common().spp;
  info.firstSample = part.sampleBegin;
  info.sampleCount = part.samples();
  return info;
}

RenderResult RenderSession::run(const RenderHooks& hooks) {
  const Scene& scene = scene_.scene();
  const RenderRequest& r = request_;
  setLaneIsa(laneIsaFor(scene_.settings().isa));
  ParallelScope parallel(r.threads);
  setMemoryLimit(scene_.settings().memoryLimit);  // the process's: another open scene may have set its own
  const Visibility& visibility = scene_.visibility();

  RenderControl control = control_;
  const RenderPart part = resolvePart(control, scene, options_->common().spp);
  FilmFileInfo info = filmInfo(visibility, part);
  const std::string filmPath = r.output.empty() ? "" : filmPathFor(r.output);
  std::optional<FilmFile> resumed;
  if (r.resume) resumed = filmToResume(filmPath, info, part);
  if (resumed) control.resume = resumed->film.get();
  bool checkpointed = false;
  control.checkpointSeconds = r.checkpointSeconds;
  control.checkpoint = [&](const lucent::Film& film) {
    writeFilmFile(filmPath, film, info);
    checkpointed = true;
  };
  control.progress = hooks.progress;
  control.stop = hooks.stop;

  RenderResult result;
  RenderOutput& out = result.render;
  out = method_->render(scene, visibility, *options_, control);
  RenderStats stats = scene_.stats();
  for (const auto& s : out.stats.stageSeconds) stats.addStage(s.first, s.second);
  nlohmann::ordered_json derived = nlohmann::ordered_json::object();
  for (const auto& [name, value] : out.stats.derived) derived[name] = value;
  info.derived = jsonText(derived);
  info.complete = out.complete;
  info.counters = out.stats.counters;
  // A part of a split render and an interrupted render keep their film (merged later, or resumed);
  // a whole render that completes removes the checkpoint it resumed from or wrote.
  const bool keepFilm = !r.output.empty() && (control.isPart() || !out.complete);
  if (!r.output.empty()) {
    std::vector<FileToWrite> alsoWrite;
    if (keepFilm) alsoWrite.push_back(filmFile(filmPath, *out.film, info));
    Stopwatch writeClock;
    writeExrAndPng(out.image, r.output, imageMetadata(info, out, ignored_, clock_.seconds(), parallel.threads()), r.png,
                   std::move(alsoWrite));
    if (!keepFilm && (checkpointed || resumed)) fs::remove(filmPath);
    stats.addStage("write_images", writeClock.seconds());
  }
  if (keepFilm) result.film = filmPath;

  nlohmann::ordered_json summary;
  summary["method"] = method_->name();
  summary["options"] = nlohmann::ordered_json::parse(info.options);
  summary["spp"] = out.sppDone;
  // Where pixels took different counts (an error target spends samples where the error is), "spp"
  // is what every pixel has; the least, mean and most are given beside it.
  if (out.film) {
    const std::span<const uint32_t> taken = out.film->samplesTaken();
    const auto [least, most] = std::minmax_element(taken.begin(), taken.end());
    if (least != taken.end() && *least != *most) {
      const double total = std::accumulate(taken.begin(), taken.end(), 0.0);
      summary["spp_per_pixel"] = {{"least", *least}, {"mean", total / double(taken.size())}, {"most", *most}};
    }
  }
  summary["complete"] = out.complete;
  if (!out.complete) summary["stopped_by"] = hooks.stoppedBy ? hooks.stoppedBy() : "stop";
  if (control.isPart()) {
    summary["crop"] = {part.region.x0, part.region.y0, part.region.x1, part.region.y1};
    summary["samples"] = {part.sampleBegin, part.samples()};
  }
  if (resumed) {
    uint64_t samples = 0;
    for (uint32_t taken : resumed->film->samplesTaken()) samples += taken;
    summary["resumed_samples"] = samples;
  }
  summary["threads"] = parallel.threads();
  summary["robust"] = scene_.settings().robust;
  summary["embree_isa"] = info.embreeIsa;
  summary["lane_isa"] = info.laneIsa;
  summary["memory_limit"] = memoryLimit();
  summary["seconds"] = clock_.seconds() + scene_.stats().stageSeconds.front().second;  // load_scene came before
  summary["setup_seconds"] = codecLoadingSeconds();  // left out of seconds
  for (const auto& [stage, seconds] : stats.stageSeconds) summary["stages"][stage] = seconds;
  for (const auto& [counter, value] : out.stats.counters) summary["counters"][counter] = value;
  summary["derived"] = derived;
  for (const auto& [key, value] : out.measured) summary[key] = measuredJson(value);
  if (!r.output.empty()) summary["output"] = r.output;
  if (!r.png.empty()) summary["png"] = r.png;
  if (keepFilm) summary["film"] = filmPath;
  summary["scene_hash"] = info.sceneHash;
  if (!ignored_.empty()) summary["ignored"] = ignored_;
  result.summary = jsonText(summary);
  return result;
}

}  // namespace lucent
