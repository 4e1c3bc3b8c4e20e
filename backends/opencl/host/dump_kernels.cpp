#include "dump_kernels.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <span>
#include <cstddef>
#include <stdexcept>

#include "lucent/core/dump.h"
#include "lucent/pipeline/shading_points.h"
#include "lucent/techniques/photons/photon.h"
#include "lucent/methods/envpbgi_records.h"
#include "lucent/methods/particles_records.h"
#include "lucent/methods/photonmap_records.h"
#include "record_fields.h"

namespace lucent::opencl {

std::vector<FieldLayout> cppRecordLayout() {
  std::vector<FieldLayout> layout;
#define LUCENT_CPP_RECORD(T) layout.push_back({#T, "", 0, uint32_t(sizeof(lucent::T))});
#define LUCENT_CPP_FIELD(T, f) \
  layout.push_back({#T, #f, uint32_t(offsetof(lucent::T, f)), uint32_t(sizeof(std::declval<lucent::T&>().f))});
  LUCENT_RECORD_FIELDS(LUCENT_CPP_RECORD, LUCENT_CPP_FIELD)
#undef LUCENT_CPP_RECORD
#undef LUCENT_CPP_FIELD
  return layout;
}

std::vector<FieldLayout> openclRecordLayout(const Device& device, const std::string& recordsSource) {
  std::vector<FieldLayout> layout = cppRecordLayout();  // the names; offsets and sizes from the device
  const Program program = device.build({recordsSource, "record_fields.h", "layout.cl"});
  const Kernel kernel = device.kernel(program, "recordLayout");
  const Buffer out = device.output(layout.size() * 2 * sizeof(uint32_t));
  setArgs(kernel, out);
  device.run(kernel, 1);
  const std::vector<uint32_t> values = device.read<uint32_t>(out, layout.size() * 2);
  for (size_t i = 0; i < layout.size(); ++i) layout[i].offset = values[2 * i], layout[i].size = values[2 * i + 1];
  return layout;
}

std::vector<std::string> layoutDifferences(const std::vector<FieldLayout>& cpp, const std::vector<FieldLayout>& cl) {
  std::vector<std::string> lines;
  if (cpp.size() != cl.size()) lines.push_back("the two lists differ in length");
  for (size_t i = 0; i < std::min(cpp.size(), cl.size()); ++i) {
    const FieldLayout &a = cpp[i], &b = cl[i];
    const std::string name = a.field.empty() ? a.record : a.record + "." + a.field;
    if (a.offset != b.offset)
      lines.push_back(name + ": offset " + std::to_string(a.offset) + " in C++, " + std::to_string(b.offset) + " in OpenCL C");
    if (a.size != b.size)
      lines.push_back(name + ": " + std::to_string(a.size) + " bytes in C++, " + std::to_string(b.size) + " in OpenCL C");
  }
  return lines;
}

namespace {

std::string file(const std::string& dir, const std::string& name) { return dir + "/" + name + ".bin"; }

// A dump is input: every index a kernel follows is checked before it reaches the device.
template <class Index>
void checkIndices(const std::vector<Index>& indices, size_t bound, const std::string& path, bool noneAllowed = false) {
  for (size_t i = 0; i < indices.size(); ++i)
    if (indices[i] >= bound && !(noneAllowed && indices[i] == Index(0xffffffffu)))
      throw std::runtime_error(path + ": entry " + std::to_string(i) + " is " + std::to_string(indices[i]) +
                               ", beyond the " + std::to_string(bound) + " it indexes");
}

template <class Offset>
void checkOffsets(const std::vector<Offset>& offsets, size_t total, const std::string& path) {
  if (!offsetsCutRuns(offsets, total)) throw std::runtime_error(path + ": not offsets from 0 to the " + std::to_string(total) + " entries they cut");
}

}  // namespace

KnnGridRun runKnnGridEstimate(const Device& device, const std::string& dumpDir, const std::string& map,
                              const std::string& band, uint32_t k, float maxRadius, uint32_t capacity) {
  const auto photons = readDump<Photon>(file(dumpDir, map + ".photons"), "Photon");
  const auto grid = readDump<UniformGrid>(file(dumpDir, map + ".grid"), "UniformGrid");
  const auto list = readDump<uint32_t>(file(dumpDir, map + ".photon_list"), "uint32");
  const auto first = readDump<uint32_t>(file(dumpDir, map + ".first_photon"), "uint32");
  const auto points = readDump<ShadingPoint>(file(dumpDir, band + ".shading_points"), "ShadingPoint");
  if (grid.size() != 1) throw std::runtime_error(file(dumpDir, map + ".grid") + ": holds " + std::to_string(grid.size()) + " grids, not 1");
  // A grid the kernel can walk: a resolution within the packed keys' bounds and int32 cell indices,
  // finite bounds and cells, a finite slack (a NaN would keep the search going for ever).
  const UniformGrid& g = grid[0];
  bool walkable = std::isfinite(g.slack) && g.slack >= 0;
  uint64_t cells = 1;
  for (int a = 0; a < 3; ++a) {
    walkable &= g.res[a] >= 1 && g.res[a] <= UniformGrid::kMaxResolution && std::isfinite(g.lo[a]) &&
                std::isfinite(g.hi[a]) && g.cellSize[a] > 0 && std::isfinite(g.cellSize[a]) && g.invCellSize[a] > 0 &&
                std::isfinite(g.invCellSize[a]);
    if (walkable) cells *= uint64_t(g.res[a]);
  }
  if (!walkable || cells > uint64_t(INT32_MAX))
    throw std::runtime_error(file(dumpDir, map + ".grid") + ": not a grid a search can walk (resolution, bounds, cells or slack out of range)");
  if (std::filesystem::exists(file(dumpDir, map + ".cell_keys")))
    throw std::runtime_error(file(dumpDir, map + ".grid") + ": a hashed grid's; the kernel reads a sorted grid (--map sort)");
  for (size_t i = 0; i < points.size(); ++i)
    if (!(std::isfinite(points[i].position.x) && std::isfinite(points[i].position.y) && std::isfinite(points[i].position.z)))
      throw std::runtime_error(file(dumpDir, band + ".shading_points") + ": point " + std::to_string(i) + " is not finite");
  if (first.size() != grid[0].cellCount() + 1)
    throw std::runtime_error(file(dumpDir, map + ".first_photon") + ": not one entry per cell and one more (a --map sort dump?)");
  checkOffsets(first, list.size(), file(dumpDir, map + ".first_photon"));
  checkIndices(list, photons.size(), file(dumpDir, map + ".photon_list"));

  const Program program = device.build({"records.cl", "knn_grid.cl"});
  const Kernel kernel = device.kernel(program, "knnGridEstimate");
  const size_t n = points.size();
  const Buffer photonBuffer = device.input(photons), listBuffer = device.input(list);
  const Buffer firstBuffer = device.input(first), gridBuffer = device.input(grid);
  const Buffer pointBuffer = device.input(points);
  const Buffer radiance = device.output(n * sizeof(Rgb)), radius2 = device.output(n * sizeof(float));
  const Buffer found = device.output(n * sizeof(uint32_t)), status = device.output(n * sizeof(uint32_t));
  const Buffer neighbours = device.output(n * capacity * sizeof(PhotonDistance));
  setArgs(kernel, photonBuffer, listBuffer, firstBuffer, gridBuffer, pointBuffer, uint32_t(n), k, maxRadius, capacity,
          radiance, radius2, found, neighbours, status);
  device.run(kernel, n);
  KnnGridRun run;
  run.capacity = capacity;
  run.radiance = device.read<Rgb>(radiance, n);
  run.radius2 = device.read<float>(radius2, n);
  run.found = device.read<uint32_t>(found, n);
  run.status = device.read<uint32_t>(status, n);
  run.neighbours = device.read<PhotonDistance>(neighbours, n * capacity);
  return run;
}

size_t writeKnnGridDumps(const KnnGridRun& run, const std::string& dumpDir, const std::string& map,
                         const std::string& band, const std::string& outDir) {
  const std::string name = band + (map == "caustic" ? ".caustic" : ".indirect");
  // Only purcell's indirect light is the global map's estimate (pmfg's is final gathering); only
  // purcell writes the searches' neighbours.
  if (!std::filesystem::exists(file(dumpDir, band + "." + map + ".neighbours")))
    throw std::runtime_error(file(dumpDir, band + "." + map + ".neighbours") + " is missing: " + name +
                             " is the " + map + " map's estimate in a purcell dump only (for pmfg, --map caustic)");
  const auto reference = readDump<Rgb>(file(dumpDir, name), "Rgb");
  if (reference.size() != run.radiance.size())
    throw std::runtime_error(file(dumpDir, name) + ": " + std::to_string(reference.size()) + " estimates for " +
                             std::to_string(run.radiance.size()) + " shading points");
  std::vector<Rgb> estimates = run.radiance;
  std::vector<uint64_t> offsets = {0};
  std::vector<PhotonDistance> neighbours;
  size_t kept = 0;
  for (size_t i = 0; i < estimates.size(); ++i) {
    if (run.status[i] == 1 || run.status[i] == 3) estimates[i] = reference[i], ++kept;
    if (run.found[i] > run.capacity)
      throw std::runtime_error("a search found " + std::to_string(run.found[i]) + " photons, more than the " +
                               std::to_string(run.capacity) + " the kernel keeps");
    const PhotonDistance* first = run.neighbours.data() + i * run.capacity;
    neighbours.insert(neighbours.end(), first, first + run.found[i]);
    offsets.push_back(neighbours.size());
  }
  writeDump(outDir, name, "Rgb", std::span(estimates));
  writeDump(outDir, band + "." + map + ".neighbour_offsets", "uint64", std::span(offsets));
  writeDump(outDir, band + "." + map + ".neighbours", "PhotonDistance", std::span(neighbours));
  return kept;
}

CacheInterpolationRun runCacheInterpolation(const Device& device, const std::string& dumpDir, float maxAngleDegrees) {
  const auto caches = readDump<RadianceCache>(file(dumpDir, "envpbgi.caches"), "RadianceCache");
  const auto begin = readDump<uint32_t>(file(dumpDir, "envpbgi.grid_begin"), "uint32");
  const auto listed = readDump<uint32_t>(file(dumpDir, "envpbgi.grid_caches"), "uint32");
  const auto points = readDump<ShadingPoint>(file(dumpDir, "shading_points"), "ShadingPoint");
  const auto tiles = readDump<uint32_t>(file(dumpDir, "envpbgi.receiver_tiles"), "uint32");
  if (tiles.size() != points.size())
    throw std::runtime_error(file(dumpDir, "envpbgi.receiver_tiles") + ": not one tile per shading point");
  checkOffsets(begin, listed.size(), file(dumpDir, "envpbgi.grid_begin"));
  checkIndices(listed, caches.size(), file(dumpDir, "envpbgi.grid_caches"));
  checkIndices(tiles, begin.size() - 1, file(dumpDir, "envpbgi.receiver_tiles"));
  const Program program = device.build({"records.cl", "radiance_cache.cl"});
  const Kernel kernel = device.kernel(program, "interpolateCaches");
  const size_t n = points.size();
  const Buffer cacheBuffer = device.input(caches), beginBuffer = device.input(begin);
  const Buffer listBuffer = device.input(listed), pointBuffer = device.input(points);
  const Buffer tileBuffer = device.input(tiles);
  const Buffer indirect = device.output(n * sizeof(Rgb)), reached = device.output(n * sizeof(uint32_t));
  const float cosMax = std::cos(maxAngleDegrees * kPi / 180.0f);  // as the renderer computes it
  setArgs(kernel, cacheBuffer, beginBuffer, listBuffer, pointBuffer, tileBuffer, uint32_t(n), cosMax, indirect, reached);
  device.run(kernel, n);
  return {device.read<Rgb>(indirect, n), device.read<uint32_t>(reached, n)};
}

size_t writeCacheDumps(const CacheInterpolationRun& run, const std::string& dumpDir, const std::string& outDir) {
  std::vector<Rgb> indirect = readDump<Rgb>(file(dumpDir, "indirect"), "Rgb");
  if (indirect.size() != run.indirect.size())
    throw std::runtime_error(file(dumpDir, "indirect") + ": not one value per shading point");
  size_t kept = 0;
  for (size_t i = 0; i < indirect.size(); ++i) {
    if (run.reached[i]) indirect[i] = run.indirect[i];
    else ++kept;
  }
  writeDump(outDir, "indirect", "Rgb", std::span(indirect));
  return kept;
}

ParticleGatheringRun runParticleGathering(const Device& device, const std::string& dumpDir) {
  const auto particles = readDump<AreaParticle>(file(dumpDir, "particles.area_particles"), "AreaParticle");
  const auto links = readDump<uint32_t>(file(dumpDir, "particles.gather_links"), "uint32");
  const auto linkParticles = readDump<uint32_t>(file(dumpDir, "particles.gather_link_particles"), "uint32");
  const auto radiance = readDump<Rgb>(file(dumpDir, "particles.radiance"), "Rgb");
  const auto offsets = readDump<uint64_t>(file(dumpDir, "particles.list_offsets"), "uint64");
  const auto listed = readDump<uint32_t>(file(dumpDir, "particles.list_particles"), "uint32");
  const auto found = readDump<uint32_t>(file(dumpDir, "particles.found_radiance_particles"), "uint32");
  const auto used = readDump<uint32_t>(file(dumpDir, "particles.used_area_particles"), "uint32");

  // --geometry all: a row per area particle, a list per radiance particle; --geometry frame: the
  // rows of gather_link_particles, a list per found radiance particle.
  const bool everyParticle = linkParticles.empty();
  ParticleGatheringRun run;
  run.rowParticle = linkParticles;
  if (everyParticle)
    for (uint32_t m = 0; m < particles.size(); ++m) run.rowParticle.push_back(m);
  const size_t rows = run.rowParticle.size();
  if (rows == 0 || links.size() % rows != 0)
    throw std::runtime_error(file(dumpDir, "particles.gather_links") + ": not a whole number of links per row");
  const uint32_t perRow = uint32_t(links.size() / rows);
  std::vector<uint32_t> listOf = found;
  if (!everyParticle)
    for (uint32_t j = 0; j < found.size(); ++j) listOf[j] = j;
  checkOffsets(offsets, listed.size(), file(dumpDir, "particles.list_offsets"));
  checkIndices(listOf, offsets.size() - 1, file(dumpDir, "particles.found_radiance_particles"));
  checkIndices(listed, particles.size(), file(dumpDir, "particles.list_particles"));
  checkIndices(run.rowParticle, particles.size(), file(dumpDir, "particles.gather_link_particles"));
  checkIndices(used, particles.size(), file(dumpDir, "particles.used_area_particles"));
  if (radiance.size() != particles.size())
    throw std::runtime_error(file(dumpDir, "particles.radiance") + ": not one value per area particle");
  checkIndices(links, particles.size(), file(dumpDir, "particles.gather_links"), true);

  const Program program = device.build({"records.cl", "particle_gathering.cl"});
  const Kernel r3 = device.kernel(program, "gatherOverLinks");
  const Buffer linkBuffer = device.input(links), radianceBuffer = device.input(radiance);
  const Buffer gathered = device.output(rows * sizeof(Rgb));
  setArgs(r3, linkBuffer, perRow, uint32_t(rows), radianceBuffer, gathered);
  device.run(r3, rows);
  run.gathered = device.read<Rgb>(gathered, rows);

  // Gathered at the used particles only, as the render does (with --geometry all every particle
  // has a row).
  std::vector<Rgb> atRow(particles.size());
  for (size_t r = 0; r < rows; ++r) atRow.at(run.rowParticle[r]) = run.gathered[r];
  run.byParticle.assign(particles.size(), Rgb());
  for (uint32_t m : used) run.byParticle.at(m) = atRow.at(m);
  const Kernel r4 = device.kernel(program, "estimateFromLists");
  const Buffer offsetBuffer = device.input(offsets), listedBuffer = device.input(listed);
  const Buffer particleBuffer = device.input(particles);
  const Buffer byParticle = device.input(run.byParticle);
  const Buffer listOfBuffer = device.input(listOf);
  const Buffer irradiance = device.output(found.size() * sizeof(Rgb));
  setArgs(r4, offsetBuffer, listedBuffer, particleBuffer, byParticle, listOfBuffer, uint32_t(found.size()), irradiance);
  device.run(r4, found.size());
  run.irradiance = device.read<Rgb>(irradiance, found.size());
  return run;
}

void writeParticleDumps(const ParticleGatheringRun& run, const std::string& outDir) {
  writeDump(outDir, "particles.gathered_irradiance", "Rgb", std::span(run.byParticle));
  writeDump(outDir, "particles.radiance_particle_irradiance", "Rgb", std::span(run.irradiance));
}

}  // namespace lucent::opencl
