// lucent render SCENE.json --method NAME [options] -o OUT.exr [--png OUT.png]
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cli/commands.h"
#include "cli/progress.h"
#include "lucent/core/parallel.h"
#include "lucent/methods/microrender.h"
#include "lucent/methods/microrender/micro_buffer.h"
#include "lucent/methods/pathtrace.h"
#include "lucent/methods/photonmap.h"
#include "lucent/methods/photons/photon_estimate.h"
#include "lucent/scene/loader.h"

namespace lucent::cli {
namespace fs = std::filesystem;

namespace {

struct RenderArgs {
  std::string scene, method = "pt", output, png, resolution, strategy = "mis";
  int threads = 0;
  int spp = 0;  // 0: the method's default
  bool quiet = false, robust = false, layers = false;
  uint64_t seed = 0;
  PathTraceOptions pt;
  PhotonMapOptions pm;
  MicroRenderOptions micro;
  std::string map, gridResolution;  // map: empty for the method's default
  std::string dump;                 // purcell, pmfg, micro: the dump directory
  std::string lighting = "direct", mapping = "warped", encoding = "float", nodeRadiance = "directional";
  bool noRayCasting = false;
  CLI::Option* photons = nullptr;  // shared by purcell, pmfg and micro, with different defaults
  // Options that belong to some methods only, with those methods, to reject them with the others.
  std::vector<std::pair<CLI::Option*, std::vector<std::string>>> methodOptions;
};

const std::vector<std::string> kMethods = {"pt", "purcell", "pmfg", "micro"};

PhotonMapKind parseMapKind(const std::string& name) {
  if (name == "sort") return PhotonMapKind::Sort;
  if (name == "stencil") return PhotonMapKind::Stencil;
  if (name == "hash") return PhotonMapKind::Hash;
  return PhotonMapKind::KdTree;
}

std::array<uint32_t, 3> parseGridResolution(const std::string& text) {
  std::array<uint32_t, 3> r{0, 0, 0};
  if (text.empty()) return r;
  long long v[3];
  char x1 = 0, x2 = 0, rest = 0;
  std::istringstream in(text);
  if (!(in >> v[0] >> x1 >> v[1] >> x2 >> v[2]) || x1 != 'x' || x2 != 'x' || (in >> rest))
    throw std::invalid_argument("--grid-resolution '" + text + "': expected XxYxZ, e.g. 25x25x50");
  for (int a = 0; a < 3; ++a) {
    if (v[a] < 1 || v[a] > (1 << 21))
      throw std::invalid_argument("--grid-resolution '" + text + "': cell counts must be in [1, 2^21]");
    r[a] = uint32_t(v[a]);
  }
  return r;
}

nlohmann::json photonMapOptionsJson(const RenderArgs& a, const Scene& scene) {
  const PhotonMapOptions& o = a.pm;
  nlohmann::json j = {{"spp", o.spp},
                      {"seed", o.seed},
                      {"photons", o.photons},
                      {"caustic_photons", o.causticPhotons},
                      {"k", o.k},
                      {"caustic_k", o.causticK > 0 ? o.causticK : o.k},
                      {"max_radius", o.maxRadius > 0 ? o.maxRadius : defaultMaxRadius(scene)},
                      {"map", a.map},
                      {"shells", o.shells},
                      {"light_samples", o.lightSamples},
                      {"max_specular_depth", o.maxSpecularDepth},
                      {"photon_bounces", o.maxPhotonBounces},
                      {"grid_resolution", a.gridResolution.empty() ? "auto" : a.gridResolution},
                      {"cell_size", o.cellSize},
                      {"photons_per_cell", o.photonsPerCell > 0 ? nlohmann::json(o.photonsPerCell) : nlohmann::json("auto")},
                      {"stencil_side", o.stencilSide},
                      {"layers", o.layers},
                      {"robust", a.robust}};
  if (a.method == "pmfg") j["gather_rays"] = o.gatherRays;
  return j;
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

nlohmann::json microOptionsJson(const RenderArgs& a, const Scene& scene) {
  const MicroRenderOptions& o = a.micro;
  nlohmann::json j = {{"spp", o.spp},
                      {"seed", o.seed},
                      {"lighting", a.lighting},
                      {"points", o.points > 0 ? o.points : defaultPointCount(scene, o.pointSpacing)},
                      {"point_spacing", o.pointSpacing},
                      {"buffer_size", o.bufferSide},
                      {"mapping", a.mapping},
                      {"table_size", o.tableSize},
                      {"ray_casting", o.rayCasting},
                      {"splat_reach", o.splatReach},
                      {"node_radiance", a.nodeRadiance},
                      {"upsampling", o.upsampling},
                      {"encoding", a.encoding},
                      {"light_samples", o.lightSamples},
                      {"point_light_samples", o.pointLightSamples},
                      {"max_specular_depth", o.maxSpecularDepth},
                      {"layers", o.layers},
                      {"robust", a.robust}};
  if (o.lighting == PointLighting::Vpl) j["vpls"] = o.vpls;
  if (o.lighting == PointLighting::Radiosity) j["radiosity_level"] = o.radiosityLevel, j["bounces"] = o.bounces;
  if (o.lighting == PointLighting::Photons) j["photons"] = o.photons, j["k"] = o.k;
  return j;
}

int runRender(RenderArgs& a) {
  const bool photonMapping = a.method == "purcell" || a.method == "pmfg";
  if (std::find(kMethods.begin(), kMethods.end(), a.method) == kMethods.end())
    throw std::invalid_argument("--method '" + a.method + "': unknown method (available: pt, purcell, pmfg, micro)");
  for (const auto& [option, methods] : a.methodOptions)
    if (option->count() > 0 && std::find(methods.begin(), methods.end(), a.method) == methods.end())
      throw std::invalid_argument(option->get_name() + " does not apply to --method " + a.method);
  a.pt.spp = a.spp > 0 ? a.spp : a.pt.spp;
  a.pt.seed = a.pm.seed = a.micro.seed = a.seed;
  a.pt.layers = a.pm.layers = a.micro.layers = a.layers;
  a.pm.dumpDirectory = a.micro.dumpDirectory = a.dump;
  if (a.spp > 0) a.pm.spp = a.micro.spp = a.spp;
  if (a.map.empty()) a.map = a.method == "pmfg" ? "kdtree" : "sort";
  a.pm.map = parseMapKind(a.map);
  a.pm.gridResolution = parseGridResolution(a.gridResolution);
  if (photonMapping) validatePhotonMapOptions(a.pm);
  if (a.method == "micro") {
    MicroRenderOptions& m = a.micro;
    m.lighting = a.lighting == "vpl"         ? PointLighting::Vpl
                 : a.lighting == "radiosity" ? PointLighting::Radiosity
                 : a.lighting == "photons"   ? PointLighting::Photons
                                             : PointLighting::Direct;
    m.mapping = a.mapping == "nusselt" ? MappingKind::Nusselt : MappingKind::Warped;
    m.encoding = a.encoding == "float" ? NodeEncoding::Float : NodeEncoding::Packed;
    m.rayCasting = !a.noRayCasting;
    m.nodeRadiance = a.nodeRadiance == "isotropic" ? NodeRadianceKind::Isotropic : NodeRadianceKind::Directional;
    // Shared option names: the photon-mapping values given on the command line.
    m.lightSamples = a.pm.lightSamples;
    m.maxSpecularDepth = a.pm.maxSpecularDepth;
    if (a.photons->count() > 0) m.photons = a.pm.photons;
    m.k = a.pm.k;
    validateMicroRenderOptions(m);
  }
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
                 {"strategy", a.strategy},    {"robust", a.robust}, {"pixel_centres", a.pt.pixelCentres}};
      out = renderPathTraced(scene, visibility, a.pt, [&](double f) { bar.update(f); });
    } else if (photonMapping) {
      options = photonMapOptionsJson(a, scene);
      const ProgressFn progress = [&](double f) { bar.update(f); };
      out = a.method == "purcell" ? renderPurcell(scene, visibility, a.pm, progress)
                                  : renderPhotonMapFinalGather(scene, visibility, a.pm, progress);
    } else {
      options = microOptionsJson(a, scene);
      out = renderMicro(scene, visibility, a.micro, [&](double f) { bar.update(f); });
    }
  }
  for (const auto& s : out.stats.stageSeconds) stats.addStage(s.first, s.second);
  stats.counters = out.stats.counters;
  const double renderSeconds = total.seconds();

  ImageMetadata meta = {{"lucent:method", a.method},
                        {"lucent:options", options.dump()},
                        {"lucent:spp", std::to_string(out.sppDone)},
                        {"lucent:seed", std::to_string(a.seed)},
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
  cmd->add_option("--method", args->method, "Rendering method: pt, purcell, pmfg, micro")->capture_default_str();
  cmd->add_option("-o,--output", args->output, "Output EXR file")->required();
  cmd->add_option("--png", args->png, "Also write an sRGB PNG");
  cmd->add_option("--spp", args->spp, "Samples per pixel (default: pt 64; purcell and pmfg 1, through the pixel centre)")
      ->check(CLI::Range(1, 1 << 24));
  cmd->add_option("--seed", args->seed, "Random seed, a non-negative integer")
      ->check(CLI::Validator(
          // CLI11 wraps a negative number into an unsigned option instead of rejecting it.
          [](std::string& value) { return value.find('-') == std::string::npos ? std::string() : "must not be negative"; },
          "NONNEGATIVE"))
      ->capture_default_str();
  cmd->add_option("--threads", args->threads, "Worker threads (0: all cores)")->check(CLI::Range(0, 4096));
  cmd->add_option("--resolution", args->resolution, "Override the camera resolution, WIDTHxHEIGHT");
  cmd->add_flag("--layers", args->layers,
                "Add albedo, normal, depth, direct and indirect layers to the EXR (purcell, pmfg: and caustic)");
  cmd->add_flag("--robust", args->robust, "Embree robust traversal mode");
  cmd->add_flag("-q,--quiet", args->quiet, "No progress bar or warnings");

  auto only = [&](CLI::Option* option, std::vector<std::string> methods) {
    args->methodOptions.emplace_back(option, std::move(methods));
  };
  const std::vector<std::string> pt = {"pt"}, pm = {"purcell", "pmfg"}, micro = {"micro"};

  // Path tracer (pt).
  only(cmd->add_option("--time-budget", args->pt.timeBudget, "pt: stop sampling within this many seconds (at least 1 spp)")
           ->check(CLI::Range(0.0, 1e9)), pt);
  only(cmd->add_option("--max-depth", args->pt.maxDepth, "pt: path length in bounces (1: direct light only)")
           ->check(CLI::Range(0, 1 << 16))->capture_default_str(), pt);
  only(cmd->add_option("--roulette-depth", args->pt.rouletteDepth, "pt: Russian roulette from this bounce on")
           ->check(CLI::Range(1, 1 << 16))->capture_default_str(), pt);
  only(cmd->add_option("--tile-size", args->pt.tileSize, "pt: tile size in pixels (does not change the image)")
           ->check(CLI::Range(1, 4096))->capture_default_str(), pt);
  only(cmd->add_option("--strategy", args->strategy, "pt: mis (default), or light or bsdf sampling alone, for validation")
           ->check(CLI::IsMember({"mis", "light", "bsdf"})), pt);
  only(cmd->add_flag("--pixel-centres", args->pt.pixelCentres,
                     "pt: every camera ray through its pixel's centre (the reference for purcell, pmfg and micro at 1 spp)"),
       pt);

  // Photon mapping (purcell, pmfg); some options are micro's too.
  PhotonMapOptions& o = args->pm;
  const std::vector<std::string> pmMicro = {"purcell", "pmfg", "micro"};
  args->photons = cmd->add_option("--photons", o.photons,
                                  "purcell, pmfg: photon paths emitted for the global map; micro: for --lighting photons (default 200000)")
                      ->check(CLI::Range(0u, 1u << 28))->capture_default_str();
  only(args->photons, pmMicro);
  only(cmd->add_option("--dump", args->dump,
                       "purcell, pmfg, micro: write every stage's arrays (photons and maps, or the point hierarchy "
                       "and its radiance; shading points, direct and indirect light) into this existing directory, "
                       "for checking another backend stage by stage (docs/dump-format.md)"),
       pmMicro);
  only(cmd->add_option("--caustic-photons", o.causticPhotons,
                       "purcell, pmfg: photon paths emitted for the caustic map, towards the mirrors and glass (0: no caustic map)")
           ->check(CLI::Range(0u, 1u << 28))->capture_default_str(), pm);
  only(cmd->add_option("--k", o.k, "purcell, pmfg, micro (--lighting photons): photons sought per radiance estimate")
           ->check(CLI::Range(1u, 1u << 20))->capture_default_str(), pmMicro);
  only(cmd->add_option("--caustic-k", o.causticK, "purcell, pmfg: photons sought in the caustic map (0: --k)")
           ->check(CLI::Range(0u, 1u << 20))->capture_default_str(), pm);
  only(cmd->add_option("--max-radius", o.maxRadius,
                       "purcell, pmfg: maximum search radius (0: 0.1 x the scene's bounding-box diagonal)")
           ->check(CLI::Range(0.0f, 1e30f))->capture_default_str(), pm);
  only(cmd->add_option("--map", args->map,
                       "purcell, pmfg: photon map: sort, stencil, hash, kdtree (default: purcell sort, pmfg kdtree)")
           ->check(CLI::IsMember({"sort", "stencil", "hash", "kdtree"})), pm);
  only(cmd->add_option("--shells", o.shells,
                       "purcell, pmfg: stop each kNN-grid search after N shells (progressive estimate; 0: to the end)")
           ->check(CLI::Range(0u, 1u << 20))->capture_default_str(), pm);
  only(cmd->add_option("--light-samples", o.lightSamples, "purcell, pmfg, micro: shadow rays per shading point")
           ->check(CLI::Range(0, 1 << 16))->capture_default_str(), pmMicro);
  only(cmd->add_option("--gather-rays", o.gatherRays, "pmfg: final-gather rays per shading point")
           ->check(CLI::Range(0, 1 << 20))->capture_default_str(), {"pmfg"});
  only(cmd->add_option("--max-specular-depth", o.maxSpecularDepth,
                       "purcell, pmfg, micro: mirror and glass bounces followed from the camera (pmfg: and by gather rays)")
           ->check(CLI::Range(0, 64))->capture_default_str(), pmMicro);
  only(cmd->add_option("--photon-bounces", o.maxPhotonBounces, "purcell, pmfg: interactions followed per photon path")
           ->check(CLI::Range(1u, 255u))->capture_default_str(), pm);
  only(cmd->add_option("--grid-resolution", args->gridResolution,
                       "purcell, pmfg: grid cells per axis, XxYxZ (default: from the photons)"), pm);
  only(cmd->add_option("--cell-size", o.cellSize, "purcell, pmfg: cubic grid cells of this side")
           ->check(CLI::Range(0.0f, 1e30f)), pm);
  only(cmd->add_option("--photons-per-cell", o.photonsPerCell,
                       "purcell, pmfg: otherwise, about this many photons per cell of the photons' bounds (0: max(1, k / 16))")
           ->check(CLI::Range(0.0f, 1e9f))->capture_default_str(), pm);
  only(cmd->add_option("--stencil-side", o.stencilSide, "purcell, pmfg: m, with m x m photons per stencil-routed cell")
           ->check(CLI::Range(1u, 1024u))->capture_default_str(), pm);

  // Micro-rendering (micro).
  MicroRenderOptions& m = args->micro;
  only(cmd->add_option("--lighting", args->lighting,
                       "micro: how the points are lit: direct (one bounce), vpl, radiosity, photons")
           ->check(CLI::IsMember({"direct", "vpl", "radiosity", "photons"}))->capture_default_str(), micro);
  only(cmd->add_option("--points", m.points, "micro: points in the hierarchy, a power of two (0: from the scene's area and the image footprint)")
           ->check(CLI::Range(0u, 1u << 31))->capture_default_str(), micro);
  only(cmd->add_option("--point-spacing", m.pointSpacing, "micro: for the default point count, the points' spacing in pixels")
           ->check(CLI::Range(0.01f, 1e6f))->capture_default_str(), micro);
  only(cmd->add_option("--buffer-size", m.bufferSide, "micro: micro-buffer side in pixels, 8 to 32")
           ->check(CLI::Range(kMinMicroBufferSide, kMaxMicroBufferSide))->capture_default_str(), micro);
  only(cmd->add_option("--mapping", args->mapping, "micro: warped (BRDF importance warping) or nusselt")
           ->check(CLI::IsMember({"warped", "nusselt"}))->capture_default_str(), micro);
  only(cmd->add_option("--table-size", m.tableSize, "micro: cells per side of the tabulated BRDF slice")
           ->check(CLI::Range(4, 256))->capture_default_str(), micro);
  only(cmd->add_flag("--no-raycast", args->noRayCasting, "micro: no post-traversal ray casting (holes, as the paper's Fig. 11)"),
       micro);
  only(cmd->add_option("--node-radiance", args->nodeRadiance,
                       "micro: what interior nodes send: isotropic (their leaves' mean, the paper's) or directional")
           ->check(CLI::IsMember({"isotropic", "directional"}))->capture_default_str(), micro);
  only(cmd->add_option("--splat-reach", m.splatReach,
                       "micro: interior nodes are splatted up to this many pixel spacings wide (1: 3 x 3 pixels, 2: 5 x 5)")
           ->check(CLI::Range(1, kMaxSplatReach))->capture_default_str(), micro);
  only(cmd->add_option("--upsampling", m.upsampling, "micro: gather at 1/N of the pixels, N = 1, 4 or 16, with bilateral upsampling")
           ->check(CLI::IsMember({1, 4, 16}))->capture_default_str(), micro);
  only(cmd->add_option("--encoding", args->encoding, "micro: float nodes, or packed (the paper's 128-bit nodes, half-float radiance)")
           ->check(CLI::IsMember({"packed", "float"}))->capture_default_str(), micro);
  only(cmd->add_option("--point-light-samples", m.pointLightSamples, "micro: shadow rays per point of the hierarchy")
           ->check(CLI::Range(0, 1 << 16))->capture_default_str(), micro);
  only(cmd->add_option("--vpls", m.vpls, "micro: light paths for virtual point lights (--lighting vpl)")
           ->check(CLI::Range(1u, 1u << 20))->capture_default_str(), micro);
  only(cmd->add_option("--radiosity-level", m.radiosityLevel, "micro: tree level gathered at (--lighting radiosity)")
           ->check(CLI::Range(1, 22))->capture_default_str(), micro);
  only(cmd->add_option("--bounces", m.bounces, "micro: Jacobi iterations (--lighting radiosity)")
           ->check(CLI::Range(0, 64))->capture_default_str(), micro);
  cmd->callback([args, &exitCode] { exitCode = runRender(*args); });
}

}  // namespace lucent::cli
