// Splitting a render (--crop, --samples) and merging the parts (lucent merge), checkpoints
// (--checkpoint), stops (SIGINT, SIGTERM) and --resume: end to end through the command line.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>
#include <tuple>

#include "lucent/image/image.h"
#include "lucent/methods/methods.h"
#include "lucent/pipeline/film_file.h"
#include "lucent/scene/loader.h"
#include "lucent/trace/visibility.h"
#include "test_support.h"

using namespace lucent;
namespace fs = std::filesystem;
using test::quoted;
using test::runLucent;

namespace {

const std::string kCornell = LUCENT_SOURCE_DIR "/scenes/cornell-box.json";
const std::string kGlass = LUCENT_SOURCE_DIR "/scenes/glass-ball.json";
const std::string kPrimitives = LUCENT_SOURCE_DIR "/scenes/primitives.json";

bool samePixels(const std::string& a, const std::string& b) {
  const Image x = readImage(a), y = readImage(b);
  return x.width() == y.width() && x.height() == y.height() && x.channels() == y.channels() &&
         std::equal(x.pixels().begin(), x.pixels().end(), y.pixels().begin(), [](float p, float q) {
           return std::memcmp(&p, &q, sizeof p) == 0;
         });
}

std::string metadata(const std::string& exr, const std::string& key) {
  ImageMetadata meta;
  readImage(exr, &meta);
  for (const auto& [k, v] : meta)
    if (k == key) return v;
  return "";
}

// Renders the part, requiring success.
void renderPart(const std::string& args, const std::string& out) {
  const test::CliRun r = runLucent("render " + args + " --quiet -o " + quoted(out));
  INFO(args << ": " << r.output);
  REQUIRE(r.status == 0);
}

// A render started in the background; its output goes to a file.
class Background {
 public:
  explicit Background(const std::string& args, const std::string& log) {
    pid_ = ::fork();
    if (pid_ == 0) {
      const std::string command = "exec " + quoted(LUCENT_CLI) + " " + args + " > " + quoted(log) + " 2>&1";
      ::execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
      ::_exit(127);
    }
  }
  void signal(int s) const { ::kill(pid_, s); }
  // The exit status, or 128 + the signal that ended it.
  int wait() {
    int status = 0;
    ::waitpid(pid_, &status, 0);
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  }

 private:
  pid_t pid_;
};

// Waits until `path` exists (a checkpoint written), at most a minute.
bool waitFor(const std::string& path) {
  for (int i = 0; i < 600 && !fs::exists(path); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  return fs::exists(path);
}

}  // namespace

TEST_CASE("A render split by crops and sample ranges merges into the single render, bit for bit", "[splits][cli]") {
  const test::TempDir dir("splits");
  struct Case {
    std::string scene, method;
  };
  // Crops off the 16-pixel tile grid, sample ranges of unequal length, layers on.
  for (const Case& c : std::vector<Case>{{kCornell, "pt --spp 5 --layers"},
                                         {kGlass, "pt --spp 5"},
                                         {kGlass, "pt --spp 5 --sampler sobol"},
                                         {kCornell, "pt --spp 5 --sampler independent --variance"},
                                         {kCornell, "pt --spp 5 --sampler independent --variance --paths"},
                                         {kGlass, "purcell --spp 5 --photons 20000 --caustic-photons 20000 --layers"},
                                         {kCornell, "pmfg --spp 5 --gather-rays 16 --photons 5000"},
                                         {kGlass, "micro --spp 5 --points 4096"},
                                         {kGlass, "micro --spp 5 --points 4096 --upsampling 4"},
                                         {kCornell, "micro --spp 5 --points 4096 --upsampling 16 --layers"},
                                         {kPrimitives, "envpbgi --spp 5 --points 16384"},
                                         {kCornell, "particles --spp 5 --area-particles 2000"}}) {
    CAPTURE(c.method);
    const std::string args = quoted(c.scene) + " --method " + c.method + " --resolution 40x30";
    renderPart(args, dir / "single.exr");
    std::string films;
    int part = 0;
    for (const char* crop : {"0,0,23,11", "23,0,40,11", "0,11,40,30"})
      for (const char* samples : {"0:2", "2:3"}) {
        const std::string out = dir / ("part" + std::to_string(part++) + ".exr");
        renderPart(args + " --crop " + crop + " --samples " + samples, out);
        REQUIRE(metadata(out, "lucent:crop") == crop);
        films.append(" ").append(quoted(fs::path(out).replace_extension(".film").string()));
      }
    const test::CliRun merge = runLucent("merge" + films + " -o " + quoted(dir / "merged.exr"));
    INFO(merge.output);
    REQUIRE(merge.status == 0);
    const auto summary = nlohmann::json::parse(merge.output);
    CHECK(summary["whole"] == true);
    CHECK(summary["merged_parts"] == 6);
    CHECK_FALSE(fs::exists(dir / "merged.film"));
    CHECK(samePixels(dir / "merged.exr", dir / "single.exr"));
    CHECK(metadata(dir / "merged.exr", "lucent:merged_parts") == "6");
  }
}

TEST_CASE("Parts that start before, inside and after contribution roulette's pilot merge into the single render",
          "[splits][cli]") {
  // The first 8 samples are the pilot; a crop or a later range traces the pilot's pixels itself.
  const test::TempDir dir("roulette-splits");
  // The primitives under sun and sky: the pilot learns the light choice too.
  for (const auto& [scene, options] : std::vector<std::pair<std::string, std::string>>{
           {kCornell, "--spp 14"}, {kCornell, "--spp 14 --sampler independent --variance --paths"}, {kPrimitives, "--spp 14"}}) {
    CAPTURE(scene, options);
    const std::string args = quoted(scene) + " --method pt " + options + " --resolution 40x30";
    renderPart(args, dir / "single.exr");
    std::string films;
    int part = 0;
    for (const char* crop : {"0,0,23,11", "23,0,40,11", "0,11,40,30"})
      for (const char* samples : {"0:5", "5:6", "11:3"}) {
        const std::string out = dir / ("part" + std::to_string(part++) + ".exr");
        renderPart(args + " --crop " + crop + " --samples " + samples, out);
        films.append(" ").append(quoted(fs::path(out).replace_extension(".film").string()));
      }
    const test::CliRun merge = runLucent("merge" + films + " -o " + quoted(dir / "merged.exr"));
    INFO(merge.output);
    REQUIRE(merge.status == 0);
    CHECK(samePixels(dir / "merged.exr", dir / "single.exr"));
    // Not vacuous: throughput roulette gives another image.
    renderPart(args + " --roulette throughput", dir / "throughput.exr");
    CHECK_FALSE(samePixels(dir / "throughput.exr", dir / "single.exr"));
  }
}

TEST_CASE("render --part divides rows and samples into N parts that merge into the single render", "[splits][cli]") {
  const test::TempDir dir("splits");
  const std::string args = quoted(kCornell) + " --spp 7 --resolution 24x17";
  renderPart(args, dir / "single.exr");
  for (const std::string axis : {"rows", "samples"}) {
    CAPTURE(axis);
    std::string films;
    for (int k = 0; k < 3; ++k) {
      const std::string out = dir / (axis + std::to_string(k) + ".exr");
      renderPart(args + " --part " + axis + ":" + std::to_string(k) + "/3", out);
      films.append(" ").append(quoted(fs::path(out).replace_extension(".film").string()));
      // 17 rows: 5, 6, 6; 7 samples: 2, 2, 3.
      const std::string expected = axis == "rows" ? std::vector<std::string>{"0,0,24,5", "0,5,24,11", "0,11,24,17"}[k]
                                                  : std::vector<std::string>{"0:2", "2:2", "4:3"}[k];
      CHECK(metadata(out, axis == "rows" ? "lucent:crop" : "lucent:samples") == expected);
    }
    const test::CliRun merge = runLucent("merge" + films + " -o " + quoted(dir / (axis + ".exr")));
    INFO(merge.output);
    REQUIRE(merge.status == 0);
    CHECK(samePixels(dir / (axis + ".exr"), dir / "single.exr"));
  }
}

TEST_CASE("merge refuses parts that do not belong together, and writes nothing", "[splits][cli]") {
  const test::TempDir dir("splits");
  const std::string args = quoted(kCornell) + " --spp 4 --resolution 24x16";
  renderPart(args + " --crop 0,0,24,8", dir / "top.exr");
  renderPart(args + " --crop 0,8,24,16 --png " + quoted(dir / "bottom.png"), dir / "bottom.exr");
  renderPart(args + " --crop 0,8,24,16 --seed 7", dir / "bottom-seed7.exr");
  renderPart(args + " --crop 0,8,24,16 --samples 0:2", dir / "bottom-half.exr");
  renderPart(args + " --crop 0,4,24,16", dir / "overlap.exr");
  renderPart(quoted(kCornell) + " --method pmfg --spp 4 --resolution 24x16 --gather-rays 4 --crop 0,8,24,16",
             dir / "bottom-pmfg.exr");
  const std::string top = quoted(dir / "top.film");
  auto merge = [&](const std::string& films) { return runLucent("merge " + films + " -o " + quoted(dir / "out.exr")); };
  for (const auto& [films, message] : std::vector<std::pair<std::string, std::string>>{
           {top + " " + quoted(dir / "bottom-seed7.film"), "its --seed is 7"},
           {top + " " + quoted(dir / "bottom-pmfg.film"), "--method pmfg"},
           {top + " " + quoted(dir / "overlap.film"), "repeats samples"},
           {top + " " + quoted(dir / "bottom-half.film"), "samples"},
           {top + " " + quoted(dir / "bottom.film") + " " + quoted(dir / "bottom-half.film"), "repeats samples"},
           {top + " " + quoted(dir / "bottom.png"), "not a Lucent film file"},
           {quoted(dir / "nothere.film"), "not found"}}) {
    const test::CliRun r = merge(films);
    INFO(films << ": " << r.output);
    CHECK(r.status == 1);
    CHECK_THAT(r.output, Catch::Contains(message));
    CHECK_FALSE(fs::exists(dir / "out.exr"));
  }
  // A damaged or truncated film is refused.
  fs::copy_file(dir / "bottom.film", dir / "damaged.film");
  {
    std::fstream f(dir / "damaged.film", std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(-20, std::ios::end);
    f.put('\x55');
  }
  CHECK_THAT(merge(top + " " + quoted(dir / "damaged.film")).output, Catch::Contains("does not match its hash"));
  fs::copy_file(dir / "bottom.film", dir / "truncated.film");
  fs::resize_file(dir / "truncated.film", fs::file_size(dir / "truncated.film") - 8);
  CHECK_THAT(merge(top + " " + quoted(dir / "truncated.film")).output, Catch::Contains("truncated or damaged"));
  // Parts of one half merge into a part: an image of the crop and a film to merge further.
  const test::CliRun half = runLucent("merge " + top + " -o " + quoted(dir / "half.exr"));
  REQUIRE(half.status == 0);
  CHECK(fs::exists(dir / "half.film"));
  // Images name the films beside them.
  const test::CliRun whole = runLucent("merge " + quoted(dir / "half.exr") + " " + quoted(dir / "bottom.exr") + " -o " +
                                       quoted(dir / "whole.exr"));
  REQUIRE(whole.status == 0);
  renderPart(args, dir / "single.exr");
  CHECK(samePixels(dir / "whole.exr", dir / "single.exr"));
}

TEST_CASE("A render killed after a checkpoint resumes to the uninterrupted image, bit for bit", "[splits][cli][resume]") {
  // Renders long enough for a checkpoint between bands (pt's 1,024 samples are about 3 s of work,
  // pmfg's bands about 2 s: its photon estimate at every gather hit keeps it there).
  const test::TempDir dir("resume");
  for (const std::string method : {"pt --spp 1024", "pmfg --spp 4 --gather-rays 128 --photons 20000 --gather-estimate photons"}) {
    CAPTURE(method);
    const std::string args = quoted(kCornell) + " --method " + method + " --resolution 96x72 --layers --quiet";
    const std::string out = dir / "out.exr", film = dir / "out.film";
    fs::remove(out), fs::remove(film);
    renderPart(args, dir / "single.exr");
    Background render("render " + args + " --checkpoint 0.3 -o " + quoted(out), dir / "log.txt");
    REQUIRE(waitFor(film));
    render.signal(SIGKILL);
    REQUIRE(render.wait() == 128 + SIGKILL);
    const FilmFile checkpoint = readFilmFile(film);
    CHECK_FALSE(checkpoint.info.complete);
    const test::CliRun resumed = runLucent("render " + args + " --resume -o " + quoted(out));
    INFO(resumed.output);
    REQUIRE(resumed.status == 0);
    const auto summary = nlohmann::json::parse(resumed.output);
    CHECK(summary["complete"] == true);
    CHECK(summary["resumed_samples"].get<uint64_t>() > 0);
    CHECK(samePixels(out, dir / "single.exr"));
    CHECK_FALSE(fs::exists(film));  // a whole render that completes removes its checkpoint
  }
}

TEST_CASE("SIGINT and SIGTERM stop a render with a checkpoint and an image marked partial", "[splits][cli][resume]") {
  const test::TempDir dir("resume");
  for (const int signal : {SIGTERM, SIGINT}) {
    CAPTURE(signal);
    const std::string args = quoted(kCornell) + " --spp 1024 --resolution 96x72 --quiet";
    const std::string out = dir / "out.exr", film = dir / "out.film";
    fs::remove(out), fs::remove(film);
    // A checkpoint first, so that the stop comes while paths are being traced (about 3 s of them).
    Background render("render " + args + " --checkpoint 0.2 -o " + quoted(out), dir / "log.txt");
    REQUIRE(waitFor(film));
    render.signal(signal);
    REQUIRE(render.wait() == 128 + signal);
    std::ifstream log(dir / "log.txt");
    const auto summary = nlohmann::json::parse(log);
    CHECK(summary["complete"] == false);
    CHECK(summary["stopped_by"] == (signal == SIGINT ? "SIGINT" : "SIGTERM"));
    CHECK(metadata(out, "lucent:partial") == "true");
    CHECK(readImage(out).width() == 96);
    CHECK_FALSE(readFilmFile(film).info.complete);
    for (const std::string& name : dir.entries()) CHECK(name.find(".lucent-tmp.") == std::string::npos);
    if (signal == SIGINT) {
      const test::CliRun resumed = runLucent("render " + args + " --resume -o " + quoted(out));
      REQUIRE(resumed.status == 0);
      renderPart(args, dir / "single.exr");
      CHECK(samePixels(out, dir / "single.exr"));
      CHECK(metadata(out, "lucent:partial").empty());
    }
  }
}

TEST_CASE("render refuses a --resume, --checkpoint, --crop or --samples it cannot do", "[splits][cli][resume]") {
  const test::TempDir dir("resume");
  const std::string args = quoted(kCornell) + " --spp 4 --resolution 24x16 --quiet";
  renderPart(args + " --samples 0:2", dir / "part.exr");
  // The part's film is not a checkpoint of a render of other options.
  fs::copy_file(dir / "part.film", dir / "other.film");
  for (const auto& [extra, message] : std::vector<std::pair<std::string, std::string>>{
           {"--seed 3 --samples 0:2 --resume -o " + quoted(dir / "other.exr"), "its --seed is 0, this render's 3"},
           {"--samples 2:2 --resume -o " + quoted(dir / "other.exr"), "--samples 0:2"},
           {"--crop 0,0,24,8 --samples 0:2 --resume -o " + quoted(dir / "other.exr"), "--crop"},
           {"--method micro --checkpoint 5 -o " + quoted(dir / "x.exr"), "cannot be checkpointed"},
           {"--time-budget 5 --samples 0:2 -o " + quoted(dir / "x.exr"), "--time-budget"},
           {"--crop 0,0,25,16 -o " + quoted(dir / "x.exr"), "not inside the 24 x 16 image"},
           {"--crop 5,0,5,16 -o " + quoted(dir / "x.exr"), "--crop"},
           {"--samples 3:2 -o " + quoted(dir / "x.exr"), "not inside the 4 samples"},
           {"--samples 3 -o " + quoted(dir / "x.exr"), "FIRST:COUNT"},
           {"--checkpoint 0 -o " + quoted(dir / "x.exr"), "--checkpoint"},
           {"--part rows:3/3 -o " + quoted(dir / "x.exr"), "--part: '3' must be in [0, 2]"},
           {"--part rows:0/17 -o " + quoted(dir / "x.exr"), "17 parts of 16 rows"},
           {"--part samples:0/5 -o " + quoted(dir / "x.exr"), "5 parts of 4 samples per pixel"},
           {"--part columns:0/2 -o " + quoted(dir / "x.exr"), "expected rows:K/N or samples:K/N"},
           {"--part rows:0/2 --crop 0,0,8,8 -o " + quoted(dir / "x.exr"), "either --part or --crop"}}) {
    const test::CliRun r = runLucent("render " + args + " " + extra);
    INFO(extra << ": " << r.output);
    CHECK(r.status == 1);
    CHECK_THAT(r.output, Catch::Contains(message));
    CHECK_FALSE(fs::exists(dir / "x.exr"));
  }
  // --resume without a film starts from the beginning.
  const test::CliRun fresh = runLucent("render " + args + " --resume -o " + quoted(dir / "fresh.exr"));
  REQUIRE(fresh.status == 0);
  CHECK_FALSE(nlohmann::json::parse(fresh.output).contains("resumed_samples"));
}

TEST_CASE("Methods that render at once refuse a library caller's checkpoints and resume by name", "[splits][resume]") {
  for (const auto& [method, scene, words] :
       {std::tuple{"micro", "cornell-box", "--method micro gathers the whole image at once"},
        std::tuple{"particles", "cornell-box", "--method particles renders the image at once"},
        std::tuple{"envpbgi", "primitives", "--method envpbgi renders the image at once"}}) {
    INFO(method);
    Scene loaded = loadScene(std::string(LUCENT_SOURCE_DIR "/scenes/") + scene + ".json", {true});
    loaded.camera.width = loaded.camera.height = 8;
    const Visibility vis(loaded);
    RenderControl control;
    control.checkpointSeconds = 5;
    control.checkpoint = [](const Film&) {};
    REQUIRE_THROWS_WITH(renderingMethod(method).render(loaded, vis, {}, control),
                        Catch::Contains(words) && Catch::Contains("cannot checkpoint or resume"));
  }
}
