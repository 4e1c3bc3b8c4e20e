#include "photon_maps.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "lucent/core/dump.h"
#include "lucent/core/memory.h"
#include "lucent/pipeline/options.h"
#include "lucent/techniques/photons/photon_tracing.h"

namespace lucent {

GridOptions gridOptionsFor(const PhotonMapOptions& options, uint32_t k) {
  GridOptions grid;
  grid.resolution = options.gridResolution;
  grid.cellSize = options.cellSize;
  // Cells of a fraction of the search radius: the kNN-grid then reads few cells and accepts few
  // photons beyond the k nearest (see the README's measurements).
  grid.photonsPerCell = options.photonsPerCell > 0 ? options.photonsPerCell : std::max(1.0f, float(k) / 16.0f);
  grid.stencilSide = options.stencilSide;
  return grid;
}

namespace {

// What a map's build takes beside its photons, per photon: keys, sorted keys and indices, and the
// photons gathered in their cells' order (the kd-tree's order, split axes and reordered photons are
// less). The grids' cell arrays are bounded by GridOptions (at most 2^24 cells).
constexpr uint64_t kMapBuildBytesPerPhoton = 64;

BuiltPhotonMap buildMap(std::vector<Photon> photons, PhotonMapKind kind, const GridOptions& grid, RenderStats& sub,
                        const std::string& what, const std::string& photonsOption) {
  BuiltPhotonMap built;
  built.photons = photons.size();
  if (photons.empty()) return built;
  requireMemory(photons.size() * kMapBuildBytesPerPhoton, "building the " + what, "lower " + photonsOption);
  switch (kind) {
    case PhotonMapKind::Sort: built.map = buildSortedGrid(std::move(photons), grid, &sub); break;
    case PhotonMapKind::Stencil: built.map = buildStencilGrid(std::move(photons), grid, &sub); break;
    case PhotonMapKind::Hash: built.map = buildHashedGrid(std::move(photons), grid, &sub); break;
    case PhotonMapKind::KdTree: built.map = buildPhotonKdTree(photons, &sub); break;
  }
  return built;
}

// The most cells a kNN-grid search may read: one that finds fewer than k photons reads every cell
// within its maximum radius. The grids chosen from the photons stay far below (the Cornell box's:
// a few thousand; GLASS BALL's paper grid, 250 x 1 x 250: 16,641); cells the options make tiny
// (--cell-size 0.001, --grid-resolution 2000000x...) would take hours per search, and are refused.
// The dense grids skip empty cells by their counts (a few lookups per empty run); the hashed grid
// has no counts and probes every cell in reach, so its searches may read no more cells than 2^16 or
// 16 per photon it holds, and at most 2^20: beyond that the cells are too small for the photons
// (GLASS BALL's paper grid, 250 x 1 x 250, passes with any photon count).
constexpr double kMaxCellsInReach = double(1 << 24);
constexpr double kMaxHashedCellsInReach = double(1 << 20);
constexpr double kHashedCellsPerPhoton = 16;

void checkSearchReach(const PhotonMapOptions& options, const BuiltPhotonMap& built, const EstimateSettings& settings) {
  if (options.cellSize <= 0 && options.gridResolution[0] == 0) return;  // chosen from the photons
  const UniformGrid* grid = nullptr;
  if (const auto* m = std::get_if<SortedGrid>(&built.map)) grid = &m->grid;
  if (const auto* m = std::get_if<StencilGrid>(&built.map)) grid = &m->grid;
  const bool hashed = std::holds_alternative<HashedGrid>(built.map);
  if (const auto* m = std::get_if<HashedGrid>(&built.map)) grid = &m->grid;
  if (!grid) return;
  double cells = 1;
  for (int a = 0; a < 3; ++a)
    cells *= std::min(double(grid->res[a]), 2 * std::ceil(double(settings.maxRadius) * grid->invCellSize[a]) + 1);
  const double limit = hashed ? std::min(kMaxHashedCellsInReach,
                                         std::max(65536.0, kHashedCellsPerPhoton * double(built.photons)))
                              : kMaxCellsInReach;
  if (!(cells <= limit))
    throw std::invalid_argument(
        std::string(options.cellSize > 0 ? "--cell-size" : "--grid-resolution") +
        ": cells this small make a search within the maximum radius (" + optionText(settings.maxRadius, OptionKind::Real) +
        ") read up to " + optionText(cells, OptionKind::Real) + " cells, more than " + optionText(limit, OptionKind::Real) +
        (hashed ? " (the hashed grid probes every cell in reach: at most 2^20, and 2^16 or 16 per photon of its " +
                      std::to_string(built.photons) + ")"
                : " (2^24)") +
        ": use larger cells, a smaller --max-radius" + (hashed ? ", or --map sort" : ""));
}

}  // namespace

MapEstimateSettings estimateSettingsFor(const Scene& scene, const PhotonMapOptions& options) {
  const float maxRadius = options.maxRadius > 0 ? options.maxRadius : defaultMaxRadius(scene);
  return {{options.k, maxRadius, options.shells},
          {options.causticK > 0 ? options.causticK : options.k, maxRadius, options.shells}};
}

RenderPhotonMaps preparePhotonMaps(const Scene& scene, const Visibility& vis, const PhotonMapOptions& options,
                                   GlobalPhotons which, RenderStats& stats) {
  RenderPhotonMaps maps;
  const MapEstimateSettings settings = estimateSettingsFor(scene, options);
  stats.addDerived("max_radius", settings.global.maxRadius);
  stats.addDerived("caustic_k", settings.caustic.k);
  maps.globalSettings = settings.global;
  maps.causticSettings = settings.caustic;

  // Two passes: the global map's photons, and the caustic map's from paths that end at their
  // first non-specular surface (so causticPhotons can be many at little cost).
  beginStage("trace_photons");
  Stopwatch traceClock;
  PhotonTracingOptions tracing;
  tracing.photons = options.photons;
  tracing.maxBounces = options.maxPhotonBounces;
  tracing.seed = options.common.seed;
  PhotonMaps global;
  if (options.photons > 0) global = tracePhotons(scene, vis, tracing);
  // Caustic paths start at a specular surface: they are emitted towards the specular objects'
  // bounding sphere only, and not at all in a scene without mirrors and glass.
  PhotonMaps caustic;
  if (options.causticPhotons > 0) tracing.target = specularTarget(scene);
  if (tracing.target) {
    tracing.photons = options.causticPhotons;
    tracing.seed = streamSeed(options.common.seed, RenderStream::CausticPhotons);
    tracing.causticOnly = true;
    tracing.photonsOption = "--caustic-photons";
    caustic = tracePhotons(scene, vis, tracing);
  }
  std::vector<Photon> globalPhotons = std::move(global.global);
  if (which == GlobalPhotons::Indirect)
    std::erase_if(globalPhotons, [](const Photon& p) { return photonBounce(p) == 0 || photonIsCaustic(p); });
  stats.addStage("trace_photons", traceClock.seconds());

  beginStage("build_map");
  Stopwatch buildClock;
  RenderStats globalSub, causticSub;
  maps.global = buildMap(std::move(globalPhotons), options.map, gridOptionsFor(options, maps.globalSettings.k), globalSub,
                         "global photon map", "--photons");
  maps.caustic = buildMap(std::move(caustic.caustic), options.map, gridOptionsFor(options, maps.causticSettings.k),
                          causticSub, "caustic photon map", "--caustic-photons");
  stats.addStage("build_map", buildClock.seconds());
  checkSearchReach(options, maps.global, maps.globalSettings);
  checkSearchReach(options, maps.caustic, maps.causticSettings);
  for (const auto& [name, s] : globalSub.stageSeconds) stats.addStage("build_map.global." + name, s);
  for (const auto& [name, s] : causticSub.stageSeconds) stats.addStage("build_map.caustic." + name, s);

  dumpPhotonMap(options, "global", maps.global);
  dumpPhotonMap(options, "caustic", maps.caustic);
  stats.addCounter("photons_emitted", uint64_t(global.emitted) + caustic.emitted);
  stats.addCounter("global_photons", maps.global.photons);
  stats.addCounter("caustic_photons", maps.caustic.photons);
  return maps;
}

void dumpPhotonMap(const PhotonMapOptions& options, const std::string& prefix, const BuiltPhotonMap& built) {
  const std::string& dir = options.shading.dumpDirectory;
  if (dir.empty()) return;
  auto dump = [&](const char* array, const char* type, const auto& records) {
    writeDump(dir, prefix + "." + array, type, std::span(records));
  };
  auto grid = [&](const UniformGrid& g, const CellCountTable& counts) {
    dump("grid", "UniformGrid", std::span(&g, 1));
    dump("cell_counts", "uint32", counts.prefix);
  };
  if (const auto* m = std::get_if<SortedGrid>(&built.map)) {
    grid(m->grid, m->cellCounts);
    dump("photons", "Photon", m->photons);
    dump("photon_list", "uint32", m->photonList);
    dump("first_photon", "uint32", m->firstPhoton);
  } else if (const auto* m = std::get_if<StencilGrid>(&built.map)) {
    grid(m->grid, m->cellCounts);
    dump("photons", "Photon", m->photons);
    dump("slots", "uint32", m->slots);
    dump("arrived", "uint32", m->arrived);
  } else if (const auto* m = std::get_if<HashedGrid>(&built.map)) {
    dump("grid", "UniformGrid", std::span(&m->grid, 1));
    dump("photons", "Photon", m->photons);
    dump("photon_list", "uint32", m->photonList);
    dump("cell_keys", "uint64", m->cellKeys);
    dump("first_photon", "uint32", m->firstPhoton);
  } else if (const auto* m = std::get_if<PhotonKdTree>(&built.map)) {
    dumpPhotonKdTree(dir, prefix, *m);
  }
}

}  // namespace lucent
