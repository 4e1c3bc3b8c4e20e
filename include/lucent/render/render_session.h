// A render as every front end runs it (`lucent render`, the Python module): a scene opened once, then
// any number of renders, each with its method, options, part and outputs checked before any work,
// rendered, and written whole with the metadata that says how it was made. A rule made here (a scene
// file cannot choose where Lucent writes; an output is never an input) holds for every front end.
#pragma once
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "lucent/core/stats.h"
#include "lucent/pipeline/method.h"
#include "lucent/pipeline/pixel_rect.h"
#include "lucent/pipeline/render_control.h"
#include "lucent/scene/loader.h"
#include "lucent/scene/scene.h"
#include "lucent/trace/visibility.h"

namespace lucent {

struct FilmFileInfo;
struct RenderPart;

// How a scene is opened for rendering.
struct SceneSettings {
  LoadOptions load;
  std::optional<std::pair<int, int>> resolution;  // width, height; none: the camera's
  // Refuse a scene whose files hold what the renders would leave out (Scene::ignored).
  bool strict = false;
  // The instruction set of Embree's kernels and of the lane loops: "" for the best this CPU runs,
  // else one of kEmbreeIsas that it runs.
  std::string isa;
  bool robust = false;       // Embree's robust traversal
  uint64_t memoryLimit = 0;  // bytes; 0: the memory in use plus the available memory
};

// A scene loaded and checked, with its Embree visibility built when the first render needs it (so
// that a render's outputs are checked before the BVH's time is spent). Throws std::invalid_argument
// or std::runtime_error naming the file for a scene that cannot be rendered.
class OpenScene {
 public:
  OpenScene(const std::string& path, const SceneSettings& settings);
  // A scene made in memory (`path` names it in the renders' metadata).
  OpenScene(Scene scene, const std::string& path, const SceneSettings& settings);
  OpenScene(const OpenScene&) = delete;
  OpenScene& operator=(const OpenScene&) = delete;

  const Scene& scene() const { return scene_; }
  const std::string& path() const { return path_; }
  const SceneSettings& settings() const { return settings_; }
  const Visibility& visibility();
  // load_scene and, once built, build_bvh.
  const RenderStats& stats() const { return stats_; }

 private:
  void prepare();  // the strict check, the resolution

  std::string path_;
  SceneSettings settings_;
  Scene scene_;
  std::unique_ptr<Visibility> visibility_;
  RenderStats stats_;
};

// One render of an open scene.
struct RenderRequest {
  std::string method;     // "": the scene file's render block's, else pt
  OptionValues options;   // over the method's defaults and the scene's render block, in order
  // How the front end spells an option in messages ("--spp" on the command line), for the options
  // given here and for those a problem names without a value given.
  std::function<std::string(const std::string& option)> optionName;
  // The files to write: the image as EXR, optionally as PNG too. "": the image stays in memory.
  std::string output, png;
  // A part of a split render (merged by `lucent merge`): the pixels of `crop` and the camera samples
  // [samples.first, samples.first + samples.second) of each (count 0: to the last), or `part`, the
  // K-th of N equal parts ("rows:K/N", "samples:K/N").
  PixelRect crop;
  std::pair<int, int> samples{0, 0};
  std::string part;
  double checkpointSeconds = 0;  // write OUT.film this often (0: never)
  bool resume = false;           // go on from OUT.film if it is a film of this render
  int threads = 0;               // 0: every core
};

// What a running render reports and is told.
struct RenderHooks {
  ProgressFn progress;
  const std::atomic<bool>* stop = nullptr;  // set from outside: the render stops within a second
  // Says what stopped an incomplete render ("SIGINT", "SIGTERM"); empty, "stop".
  std::function<std::string()> stoppedBy;
};

struct RenderResult {
  RenderOutput render;
  std::string film;     // the film file written beside the output (a part, an interrupted render), or ""
  std::string summary;  // one line of JSON: method, options, spp, stages, counters, outputs, ...
};

class RenderSession {
 public:
  // Checks all that can be checked before rendering, or throws std::invalid_argument (OptionError
  // for an option's value) naming what is wrong: the method; its options over the scene file's
  // render block (which cannot choose where Lucent writes); the outputs (the right extensions,
  // writable, none of them a file the scene reads, none of the scene's files in a dump directory
  // under a dump file's name); the part; the film to resume from.
  RenderSession(OpenScene& scene, RenderRequest request);
  ~RenderSession();
  RenderSession(const RenderSession&) = delete;
  RenderSession& operator=(const RenderSession&) = delete;

  const Method& method() const { return *method_; }
  const MethodOptions& options() const { return *options_; }

  // Renders and writes the outputs whole (never a partial file). A stop before any sample throws
  // RenderStopped and writes nothing; a later one returns the samples taken, complete false, with
  // the film kept beside the output to resume from.
  RenderResult run(const RenderHooks& hooks = {});

 private:
  FilmFileInfo filmInfo(const Visibility& visibility, const RenderPart& part) const;

  OpenScene& scene_;
  RenderRequest request_;
  const Method* method_ = nullptr;
  std::unique_ptr<MethodOptions> options_;
  // What the render leaves out of what the scene's files hold: the scene's list (Scene::ignored) and
  // what this method does not render of it.
  std::vector<std::string> ignored_;
  RenderControl control_;  // the part
  Stopwatch clock_;
};

}  // namespace lucent
