// `lucent render` end to end: outputs, metadata, the JSON summary, layers and the time budget.
#include <catch2/catch.hpp>
#include <algorithm>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "lucent/image/image.h"
#include "lucent/scene/loader.h"
#include "test_support.h"

using namespace lucent;
namespace fs = std::filesystem;

namespace {

using test::runLucent;

const std::string kScene = LUCENT_SOURCE_DIR "/scenes/cornell-box.json";

}  // namespace

TEST_CASE("render writes EXR and PNG with metadata and prints one JSON summary", "[cli][render]") {
  const test::TempDir dir("render-cli");
  const std::string exr = dir / "out.exr", png = dir / "out.png";
  const test::CliRun r = runLucent("render " + kScene + " --method pt --spp 2 --seed 3 --threads 2 --resolution 40x30 -o " + exr +
                    " --png " + png + " --layers");
  INFO(r.output);
  REQUIRE(r.status == 0);
  const auto summary = nlohmann::json::parse(r.output);
  REQUIRE(summary["method"] == "pt");
  REQUIRE(summary["spp"] == 2);
  REQUIRE(summary["options"]["seed"] == 3);
  REQUIRE(summary["counters"]["samples"] == 40 * 30 * 2);
  REQUIRE(summary["stages"].contains("build_bvh"));
  REQUIRE(summary["stages"].contains("trace_paths"));
  REQUIRE(fs::exists(png));

  ImageMetadata meta;
  const Image image = readImage(exr, &meta);
  REQUIRE(image.width() == 40);
  REQUIRE(image.height() == 30);
  for (const char* c : {"R", "G", "B", "albedo.R", "normal.X", "depth.Z", "direct.G", "indirect.B"})
    REQUIRE(image.channelIndex(c) >= 0);
  auto value = [&](const std::string& key) {
    for (const auto& [k, v] : meta)
      if (k == key) return v;
    FAIL("metadata key " << key << " missing");
    return std::string();
  };
  REQUIRE(value("lucent:method") == "pt");
  REQUIRE(value("lucent:spp") == "2");
  REQUIRE(value("lucent:seed") == "3");
  REQUIRE(value("lucent:embree_version").rfind("3.", 0) == 0);
  REQUIRE(!value("lucent:embree_isa").empty());
  REQUIRE(value("lucent:scene_hash") == summary["scene_hash"]);
  REQUIRE(nlohmann::json::parse(value("lucent:options"))["spp"] == 2);
  REQUIRE(!value("lucent:render_seconds").empty());
  REQUIRE(!value("lucent:version").empty());

  // The layers add up: beauty = direct + indirect.
  const int r0 = image.channelIndex("R"), d0 = image.channelIndex("direct.R"), i0 = image.channelIndex("indirect.R");
  for (int y = 0; y < 30; ++y)
    for (int x = 0; x < 40; ++x)
      REQUIRE(image.at(x, y, r0) == Approx(image.at(x, y, d0) + image.at(x, y, i0)).margin(1e-5));
}

TEST_CASE("render: the JSON's seconds are its stages', not the process's set-up", "[cli][render]") {
  // Loading the image writer is set-up: a render of 8 x 8 pixels at 1 spp spends milliseconds
  // outside its stages.
  const test::TempDir dir("render-seconds");
  const test::CliRun r = runLucent("render " + kScene + " --spp 1 --threads 2 --resolution 8x8 -o " + (dir / "out.exr"));
  INFO(r.output);
  REQUIRE(r.status == 0);
  const auto summary = nlohmann::json::parse(r.output);
  double stages = 0;
  for (const auto& [stage, seconds] : summary["stages"].items()) stages += seconds.get<double>();
  CHECK(summary["seconds"].get<double>() - stages < 0.15);
}

TEST_CASE("render: loading the texture reader is set-up, left out of load_scene", "[cli][render]") {
  // A quad with a PNG texture: its first read loads OpenImageIO (about 0.25 s of dynamic linking
  // in a new process), far more than the scene's own loading; the JSON gives it as setup_seconds.
  const test::TempDir dir("render-setup");
  Image texel(2, 2, {"R", "G", "B"});
  writePng(texel, dir / "texture.png");
  std::ofstream(dir / "quad.mtl") << "newmtl textured\nKd 1 1 1\nmap_Kd texture.png\n";
  std::ofstream(dir / "quad.obj") << "mtllib quad.mtl\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n"
                                     "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl textured\nf 1/1 2/2 3/3 4/4\n";
  std::ofstream(dir / "scene.json") << R"({"camera": {"eye": [0, 0, 3], "look_at": [0, 0, 0], "up": [0, 1, 0],
    "fov_y": 40, "resolution": [8, 8]}, "meshes": [{"obj": "quad.obj"}],
    "lights": [{"type": "point", "position": [0, 0, 2], "power": [10, 10, 10]}]})";
  const test::CliRun r = runLucent("render " + (dir / "scene.json") + " --spp 1 -q -o " + (dir / "out.exr"));
  INFO(r.output);
  REQUIRE(r.status == 0);
  const auto summary = nlohmann::json::parse(r.output);
  const double setup = summary["setup_seconds"].get<double>(), load = summary["stages"]["load_scene"].get<double>();
  CHECK(setup > 0.02);
  CHECK(load < 0.5 * setup);  // with OpenImageIO's loading in it, load_scene would exceed setup
}

TEST_CASE("render: an untextured scene's EXR and PNG are written, and EXRs compared, without loading OpenImageIO", "[cli][render]") {
  // OpenImageIO's 260 libraries take a process 0.3 s of CPU to load; OpenEXR's and libpng's a few
  // milliseconds. The dynamic loader names every object it opens (LD_DEBUG=files).
  const test::TempDir dir("render-writer");
  const test::CliRun r = test::runCommand("LD_DEBUG=files " + test::quoted(LUCENT_CLI) + " render " + kScene +
                                          " --spp 1 --resolution 8x8 -q -o " + (dir / "out.exr") + " --png " +
                                          (dir / "out.png"));
  INFO(r.output.substr(0, 2000));
  REQUIRE(r.status == 0);
  CHECK(r.output.find("liblucent_image_exr.so") != std::string::npos);
  CHECK(r.output.find("libOpenImageIO") == std::string::npos);
  const test::CliRun compare = test::runCommand("LD_DEBUG=files " + test::quoted(LUCENT_CLI) + " compare " +
                                                (dir / "out.exr") + " " + (dir / "out.exr"));
  CHECK(compare.status == 0);
  CHECK(compare.output.find("\"relmse\":0") != std::string::npos);
  CHECK(compare.output.find("libOpenImageIO") == std::string::npos);
  // The PNG is read by OpenImageIO: the check above can fail.
  const test::CliRun png = test::runCommand("LD_DEBUG=files " + test::quoted(LUCENT_CLI) + " compare --ldr " +
                                            (dir / "out.png") + " " + (dir / "out.exr"));
  CHECK(png.output.find("libOpenImageIO") != std::string::npos);
  CHECK(readImage(dir / "out.png").width() == 8);
  CHECK(readImage(dir / "out.exr").channelIndex("R") >= 0);
}

TEST_CASE("render: same seed gives the same pixels with 1 and 2 threads, another seed differs", "[cli][render][determinism]") {
  const test::TempDir dir("render-cli");
  auto render = [&](const std::string& name, const std::string& extra) {
    const std::string exr = dir / name;
    const test::CliRun r = runLucent("render " + kScene + " --spp 4 --resolution 32x32 --quiet -o " + exr + " " + extra);
    INFO(r.output);
    REQUIRE(r.status == 0);
    return readImage(exr).pixels();
  };
  const auto a = render("a.exr", "--threads 1 --tile-size 8");
  const auto b = render("b.exr", "--threads 2 --tile-size 13");
  const auto c = render("c.exr", "--threads 2 --seed 1");
  REQUIRE(a == b);
  REQUIRE(a != c);
}

TEST_CASE("render: a time budget stops early and records the samples taken", "[cli][render]") {
  const test::TempDir dir("render-cli");
  const std::string exr = dir / "out.exr";
  const test::CliRun r = runLucent("render " + kScene + " --spp 1000000 --time-budget 0.5 --resolution 64x64 --quiet -o " + exr);
  INFO(r.output);
  REQUIRE(r.status == 0);
  const auto summary = nlohmann::json::parse(r.output);
  const int spp = summary["spp"];
  REQUIRE(spp >= 1);
  REQUIRE(spp < 1000000);
  REQUIRE(summary["seconds"].get<double>() < 30.0);
  ImageMetadata meta;
  readImage(exr, &meta);
  bool found = false;
  for (const auto& [k, v] : meta) found |= (k == "lucent:spp" && v == std::to_string(spp));
  REQUIRE(found);
}

TEST_CASE("render: a time budget's image is the image of the samples it took", "[cli][render][roulette]") {
  // Its passes end at contribution roulette's pilot (8 samples), so it continues with the scales of
  // a render without a budget.
  const test::TempDir dir("render-cli");
  const std::string budget = dir / "budget.exr", fixed = dir / "fixed.exr";
  const std::string args = "render " + kScene + " --resolution 16x12 --threads 2 --quiet";
  const test::CliRun r = runLucent(args + " --spp 1000000 --time-budget 0.5 -o " + budget);
  INFO(r.output);
  REQUIRE(r.status == 0);
  const int spp = nlohmann::json::parse(r.output)["spp"];
  REQUIRE(spp > 8);  // past the pilot
  REQUIRE(runLucent(args + " --spp " + std::to_string(spp) + " -o " + fixed).status == 0);
  CHECK(readImage(budget).pixels() == readImage(fixed).pixels());
}

TEST_CASE("render --method purcell and pmfg: options, the paper's stages and metadata", "[cli][render][photonmap]") {
  const test::TempDir dir("render-cli");
  for (const std::string method : {"purcell", "pmfg"}) {
    const std::string exr = dir / (method + ".exr");
    const test::CliRun r =
        runLucent("render " + kScene + " --method " + method + " --photons 5000 --caustic-photons 0 --k 20 --seed 5" +
                  " --light-samples 2 --resolution 24x20 --threads 2 --layers --quiet -o " + exr +
                  (method == "pmfg" ? " --gather-rays 8" : " --map stencil --shells 2"));
    INFO(r.output);
    REQUIRE(r.status == 0);
    const auto summary = nlohmann::json::parse(r.output);
    REQUIRE(summary["method"] == method);
    REQUIRE(summary["spp"] == 1);
    const auto& options = summary["options"];
    REQUIRE(options["photons"] == 5000);
    REQUIRE(options["caustic_photons"] == 0);
    REQUIRE(options["k"] == 20);
    REQUIRE(options["seed"] == 5);
    REQUIRE(options["light_samples"] == 2);
    REQUIRE(options["map"] == (method == "pmfg" ? "kdtree" : "stencil"));
    REQUIRE(options["max_radius"] == 0);                                 // as given: from the scene
    REQUIRE(summary["derived"]["max_radius"].get<double>() > 0);         // and the value it stood for
    REQUIRE(summary["derived"]["caustic_k"] == 20);
    for (const char* key : {"caustic_k", "shells", "max_specular_depth", "photon_bounces", "grid_resolution",
                            "cell_size", "photons_per_cell", "stencil_side", "spp", "layers"})
      REQUIRE(options.contains(key));
    REQUIRE(options.contains("gather_rays") == (method == "pmfg"));
    for (const char* stage : {"trace_photons", "build_map", "trace_rays", "radiance_estimate"})
      REQUIRE(summary["stages"].contains(stage));
    REQUIRE(summary["counters"]["global_photons"].get<int>() > 5000);
    REQUIRE(summary["counters"]["caustic_photons"] == 0);

    ImageMetadata meta;
    const Image image = readImage(exr, &meta);
    REQUIRE(image.width() == 24);
    for (const char* c : {"R", "albedo.R", "depth.Z", "direct.G", "indirect.B", "caustic.R"})
      REQUIRE(image.channelIndex(c) >= 0);
    std::string metaMethod, metaOptions;
    for (const auto& [k, v] : meta) {
      if (k == "lucent:method") metaMethod = v;
      if (k == "lucent:options") metaOptions = v;
    }
    REQUIRE(metaMethod == method);
    REQUIRE(nlohmann::json::parse(metaOptions) == options);
  }
}

TEST_CASE("render: impossible photon-mapping options are rejected with a message and no output", "[cli][render][photonmap]") {
  const test::TempDir dir("render-cli");
  const std::string exr = dir / "out.exr";
  for (const auto& [args, message] : std::vector<std::pair<std::string, std::string>>{
           {"--method purcell --map kdtree --shells 3", "shells"},
           {"--method purcell --gather-rays 16", "--gather-rays"},
           {"--method pt --photons 1000", "--photons"},
           {"--method pmfg --time-budget 2", "--time-budget"},
           {"--method pmfg --grid-resolution 25x25", "--grid-resolution"},
           // Searches that would read billions of cells (they ran for hours) are refused at once.
           {"--method purcell --map hash --cell-size 1e-5", "--cell-size"},
           {"--method purcell --map hash --grid-resolution 2000x2000x2000 --max-radius 100", "--grid-resolution"}}) {
    const test::CliRun r = runLucent("render " + kScene + " " + args + " --resolution 8x8 --quiet -o " + exr);
    INFO(args << ": " << r.output);
    REQUIRE(r.status == 1);
    REQUIRE(r.output.find(message) != std::string::npos);
    REQUIRE(dir.entries().empty());
  }
}

TEST_CASE("render --method micro: options, the paper's time breakdown and counters, metadata", "[cli][render][microrender]") {
  const test::TempDir dir("render-cli");
  for (const std::string lighting : {"direct", "vpl", "radiosity", "photons"}) {
    const std::string exr = dir / (lighting + ".exr");
    // Half of the runs with the paper's node radiance and 3 x 3 splats, half with the defaults.
    const bool paperNodes = lighting == "direct" || lighting == "radiosity";
    const test::CliRun r = runLucent("render " + kScene + " --method micro --lighting " + lighting +
                                     (paperNodes ? " --node-radiance isotropic --splat-reach 1" : "") +
                                     " --points 4096 --buffer-size 16 --mapping nusselt --upsampling 4 --encoding packed"
                                     " --light-samples 4 --point-light-samples 2 --vpls 16 --radiosity-level 6 --bounces 1"
                                     " --photons 2000 --k 10 --resolution 24x20 --seed 4 --threads 2 --layers --quiet -o " + exr);
    INFO(r.output);
    REQUIRE(r.status == 0);
    const auto summary = nlohmann::json::parse(r.output);
    REQUIRE(summary["method"] == "micro");
    const auto& options = summary["options"];
    REQUIRE(options["lighting"] == lighting);
    REQUIRE(options["points"] == 4096);
    REQUIRE(options["buffer_size"] == 16);
    REQUIRE(options["mapping"] == "nusselt");
    REQUIRE(options["upsampling"] == 4);
    REQUIRE(options["encoding"] == "packed");
    REQUIRE(options["light_samples"] == 4);
    REQUIRE(options["ray_casting"] == true);
    REQUIRE(options["node_radiance"] == (paperNodes ? "isotropic" : "directional"));
    REQUIRE(options["splat_reach"] == (paperNodes ? 1 : 2));
    REQUIRE(options["vpls"] == 16);
    REQUIRE(options["bounces"] == 1);
    REQUIRE(options["photons"] == 2000);
    for (const char* stage : {"hierarchy_update", "point_lighting", "build_mappings", "evaluate_mappings", "rasterize",
                              "ray_casting", "upsampling", "eye_rays_and_direct_light"})
      REQUIRE(summary["stages"].contains(stage));
    for (const char* counter : {"micro_buffers", "micro_buffers_ray_cast", "nodes_visited", "gather_samples"})
      REQUIRE(summary["counters"].contains(counter));
    REQUIRE(summary["counters"]["micro_buffers"].get<int>() > 0);
    std::string metaOptions;
    ImageMetadata meta;
    const Image image = readImage(exr, &meta);
    for (const auto& [k, v] : meta)
      if (k == "lucent:options") metaOptions = v;
    REQUIRE(nlohmann::json::parse(metaOptions) == options);
    REQUIRE(image.channelIndex("indirect.R") >= 0);
  }
  // Without a point count the scene's area and the image footprint decide, and it is written down.
  const test::CliRun r = runLucent("render " + kScene + " --method micro --resolution 16x16 --quiet -o " + (dir / "d.exr"));
  INFO(r.output);
  REQUIRE(r.status == 0);
  REQUIRE(nlohmann::json::parse(r.output)["options"]["points"] == 0);
  REQUIRE(nlohmann::json::parse(r.output)["derived"]["points"].get<int>() >= 4096);
}

TEST_CASE("render: impossible micro options are rejected with a message and no output", "[cli][render][microrender]") {
  const test::TempDir dir("render-cli");
  const std::string exr = dir / "out.exr";
  for (const auto& [args, message] : std::vector<std::pair<std::string, std::string>>{
           {"--method micro --points 1000", "power of two"},
           {"--method micro --points 16777216", "--points: '16777216' must be in [0, 2^23]"},
           {"--method micro --buffer-size 40", "--buffer-size"},
           {"--method micro --upsampling 3", "--upsampling"},
           {"--method micro --lighting sunlight", "--lighting"},
           {"--method micro --splat-reach 3", "--splat-reach"},
           {"--method micro --node-radiance mean", "--node-radiance"},
           {"--method pt --splat-reach 1", "--splat-reach"},
           {"--method micro --gather-rays 16", "--gather-rays: an option of --method pmfg, not of --method micro"},
           {"--method pmfg --no-ray-casting", "--ray-casting: an option of --method micro, not of --method pmfg"},
           {"--method micro --no-raycast", "unknown option --no-raycast"},
           {"--method pt --lighting vpl", "--lighting"}}) {
    const test::CliRun r = runLucent("render " + kScene + " " + args + " --resolution 8x8 --quiet -o " + exr);
    INFO(args << ": " << r.output);
    REQUIRE(r.status != 0);
    REQUIRE(r.output.find(message) != std::string::npos);
    REQUIRE(dir.entries().empty());
  }
}

TEST_CASE("render writes its outputs as one and touches no other file", "[cli][render]") {
  const test::TempDir dir("render-cli");
  // A scene beside its own environment map.
  Image sky(4, 2, {"R", "G", "B"});
  for (float& v : sky.pixels()) v = 0.5f;
  writeExr(sky, dir / "sky.exr");
  std::ofstream(dir / "scene.json") << R"({"camera": {"eye": [0, 0.5, 3], "look_at": [0, 0.5, 0], "up": [0, 1, 0],
    "fov_y": 45, "resolution": [8, 8]}, "meshes": [{"obj": ")" LUCENT_SOURCE_DIR R"(/tests/data/good/base/base.obj"}],
    "lights": [{"type": "environment", "map": "sky.exr"}]})";
  const std::string scene = test::quoted(dir / "scene.json");
  const auto skyBefore = fs::last_write_time(dir / "sky.exr");
  SECTION("an output that is one of the scene's files is refused") {
    const test::CliRun r = runLucent("render " + scene + " --spp 1 --quiet -o " + test::quoted(dir / "sky.exr"));
    CHECK(r.status == 1);
    CHECK_THAT(r.output, Catch::Contains("a file this process reads"));
    CHECK(fs::last_write_time(dir / "sky.exr") == skyBefore);
    const test::CliRun same = runLucent("render " + scene + " --spp 1 --quiet -o " + test::quoted(dir / "a.exr") +
                                        " --png " + test::quoted(dir / "scene.json"));
    CHECK(same.status == 1);
  }
  SECTION("a PNG that cannot be written leaves no EXR and no temporary file") {
    fs::create_directory(dir / "out.png");  // a directory: the PNG cannot take its place
    const test::CliRun r = runLucent("render " + scene + " --spp 1 --quiet -o " + test::quoted(dir / "out.exr") +
                                     " --png " + test::quoted(dir / "out.png"));
    INFO(r.output);
    CHECK(r.status == 1);
    CHECK_FALSE(fs::exists(dir / "out.exr"));
    for (const std::string& name : dir.entries()) CHECK(name.find(".lucent-tmp.") == std::string::npos);
  }
  SECTION("other programs' files that look like temporary files are kept, whatever their names") {
    const std::vector<std::string> foreign = {".notes.tmp-4000000-1.txt", ".out.tmp-999999999-0.exr",
                                              ".x.tmp-99999999999999999999-0.exr", ".out.tmp-1-0.exr"};
    for (const std::string& name : foreign) std::ofstream(dir / name) << "someone's data";
    const test::CliRun r = runLucent("render " + scene + " --spp 1 --quiet -o " + test::quoted(dir / "out.exr"));
    INFO(r.output);
    CHECK(r.status == 0);
    for (const std::string& name : foreign) CHECK(fs::exists(dir / name));
    CHECK(fs::exists(dir / "out.exr"));
  }
}

TEST_CASE("Every command's bad arguments exit 1, compare's 2, and help 0", "[cli]") {
  CHECK(runLucent("--help").status == 0);
  CHECK(runLucent("render --help").status == 0);
  CHECK(runLucent("methods --bogus").status == 1);
  CHECK(runLucent("compare a.exr").status == 2);
  CHECK(runLucent("compare a.exr b.exr --metric psnr").status == 2);
  CHECK(runLucent("compare a.exr b.exr --max-error -1").status == 2);
  const test::CliRun nan = runLucent("compare a.exr b.exr --max-error nan");
  CHECK(nan.status == 2);
  CHECK_THAT(nan.output, Catch::Contains("--max-error must be a finite number"));
  CHECK(runLucent("render " + kScene + " --spp x -o x.exr").status == 1);
  const test::CliRun threads = runLucent("render " + kScene + " --threads -2 -o x.exr");
  CHECK(threads.status == 1);
  CHECK_THAT(threads.output, Catch::Contains("--threads: '-2'"));
  CHECK(runLucent("nonsense").status == 1);
  CHECK(runLucent("merge").status == 1);
}

TEST_CASE("lucent bsdf lists a scene's materials and gives one's albedo, f and pdf as CSV or JSON", "[cli][bsdf]") {
  const std::string scene = LUCENT_SOURCE_DIR "/scenes/cornell-box.json";
  const test::CliRun list = test::runLucent("bsdf " + scene);
  INFO(list.output);
  REQUIRE(list.status == 0);
  CHECK_THAT(list.output, Catch::Contains(",white,diffuse\n"));
  // A Lambertian material: E = kd at every angle; f = kd / pi and pdf = cos / pi for a pair.
  const Scene loaded = loadScene(scene, {true});
  const auto white = std::find(loaded.materialNames.begin(), loaded.materialNames.end(), "white");
  REQUIRE(white != loaded.materialNames.end());
  const Rgb kd = loaded.materials[size_t(white - loaded.materialNames.begin())].kd;
  const test::CliRun r = test::runLucent("bsdf " + scene + " white --cosines 3 --samples 64 --wo 0,0,1 --wi 0,0.6,0.8 --json");
  INFO(r.output);
  REQUIRE(r.status == 0);
  const nlohmann::json j = nlohmann::json::parse(r.output);
  CHECK(j["type"] == "diffuse");
  REQUIRE(j["directional_albedo"].size() == 3);
  for (const auto& e : j["directional_albedo"])
    for (int c = 0; c < 3; ++c) CHECK(e["albedo"][c].get<double>() == Approx(kd[c]).epsilon(1e-6));
  for (int c = 0; c < 3; ++c) CHECK(j["f"][c].get<double>() == Approx(kd[c] / kPi).epsilon(1e-6));
  CHECK(j["pdf"].get<double>() == Approx(0.8 / kPi).epsilon(1e-6));
  const test::CliRun csv = test::runLucent("bsdf " + scene + " white --cosines 2 --samples 64");
  CHECK(csv.status == 0);
  CHECK_THAT(csv.output, Catch::StartsWith("cos_theta,albedo_r,albedo_g,albedo_b,error_r,error_g,error_b\n0.25,"));
  // A name that is no material's, one direction without the other, a zero direction and a missing
  // scene are refused, each with its message.
  for (const auto& [args, message] : {std::pair<std::string, std::string>{scene + " velvet", "'velvet' is neither the name nor the index"},
                                      {scene + " white --wo 0,0,1", "--wo and --wi: give both"},
                                      {scene + " white --wo 0,0,0 --wi 0,0,1", "--wo: not a direction"},
                                      {"no-such-scene.json", "no-such-scene.json"}}) {
    const test::CliRun refused = test::runLucent("bsdf " + args);
    INFO(args);
    CHECK(refused.status == 1);
    CHECK_THAT(refused.output, Catch::Contains(message));
  }
  CHECK(test::runLucent("bsdf " + scene + " white --cosines 0").status == 1);
  // A thin-walled transmitting glTF material is two-sided: albedos from above only, with the light it
  // passes (the tinted shell: about 0.04 + 0.96 base colour at normal incidence; 0.13 in red without).
  const test::CliRun shell = test::runLucent(std::string("bsdf ") + LUCENT_SOURCE_DIR
                                             "/scenes/gltf/extensions.glb 'tinted shell' --cosines 4 --samples 4096 --json");
  INFO(shell.output);
  REQUIRE(shell.status == 0);
  const nlohmann::json s = nlohmann::json::parse(shell.output);
  REQUIRE(s["directional_albedo"].size() == 4);
  for (const auto& e : s["directional_albedo"]) CHECK(e["cos_theta"].get<double>() > 0);
  CHECK(s["directional_albedo"][3]["albedo"][0].get<double>() > 0.8);
}
