// --method particles: the paper's three stages (Fig. 4). Geometry: area particles, their
// scattering and gathering links, the tessellation into radiance particles and their estimation
// lists. Lighting: emission into the particles, scattering along the links. Ray tracing: camera
// paths through mirrors and glass to shading points (the preliminary ray tracing, whose hits the
// final one reuses), the radiance particles around them and the area particles of their lists,
// gathering at those, radiance estimation at these, and at every shading point direct light by
// shadow rays plus the interpolated indirect light.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include "lucent/core/dump.h"
#include "lucent/core/memory.h"
#include "lucent/pipeline/direct_light.h"
#include "lucent/pipeline/dumps.h"
#include "lucent/pipeline/film.h"
#include "lucent/pipeline/render_control.h"
#include "lucent/pipeline/shading_points.h"
#include "methods/particles/particle_lighting.h"
#include "methods/particles/particle_links.h"
#include "methods/particles/particles.h"
#include "methods/particles/radiance_particles.h"

namespace lucent {

namespace {

enum class ParticleStream : uint64_t { Positions = 41, ScatterLinks = 42, GatherLinks = 43, Emission = 44, Scattering = 45, Areas = 46 };
uint64_t particleSeed(uint64_t seed, ParticleStream s) { return hashKey(seed, uint64_t(s)); }

// The barycentrics (b1, b2) of p in a triangle (p on it, as a hit's position is).
Vec2 barycentricsOf(const Scene& scene, uint32_t tri, Vec3 p) {
  const Vec3 v0 = scene.vertex(tri, 0), e1 = scene.vertex(tri, 1) - v0, e2 = scene.vertex(tri, 2) - v0, d = p - v0;
  const float d00 = dot(e1, e1), d01 = dot(e1, e2), d11 = dot(e2, e2), d20 = dot(d, e1), d21 = dot(d, e2);
  const float den = d00 * d11 - d01 * d01;
  if (!(den > 0)) return {0, 0};
  return {(d11 * d20 - d01 * d21) / den, (d00 * d21 - d01 * d20) / den};
}

// Which side's radiance particles a shading point reads.
uint32_t sideOf(const ShadingPoint& p, uint32_t sides) {
  return sides == 2 && dot(p.wo, p.geometricNormal) < 0 ? 1u : 0u;
}

std::vector<uint32_t> markedIndices(const std::vector<uint8_t>& marks) {
  std::vector<uint32_t> out;
  for (size_t i = 0; i < marks.size(); ++i)
    if (marks[i]) out.push_back(uint32_t(i));
  return out;
}

}  // namespace

RenderOutput renderParticles(const Scene& scene, const Visibility& vis, const ParticleOptions& o,
                             const RenderControl& control) {
  particleOptionTable().validate(o);
  if (control.resume || control.checkpointSeconds > 0)
    throw std::invalid_argument("--method particles renders the image at once and cannot checkpoint or resume; "
                                "render it in parts (--crop, --samples) to bound the work a kill loses");
  const RenderPart part = resolvePart(control, scene, o.spp);
  RenderOutput out;
  RenderStats& stats = out.stats;
  auto report = [&](double fraction) {
    if (control.progress) control.progress(fraction);
  };
  const std::string& dump = o.dumpDirectory;

  // Geometry stage (4.1). G1: area particles.
  const uint32_t sides = o.sides == ParticleSides::Both ? 2 : 1;
  const uint64_t scatterPer = uint64_t(o.scatterLinks) * uint64_t(o.scatterLinks);
  const uint64_t gatherPer = uint64_t(o.gatherLinks) * uint64_t(o.gatherLinks);
  const uint64_t particleCount = uint64_t(o.areaParticles) * sides;
  requireMemory(particleCount * (sizeof(AreaParticle) + 4 * (scatterPer + gatherPer) + 6 * sizeof(Rgb) + 16) +
                    uint64_t(o.areaParticles) * o.areaSamples * sizeof(PointSample),
                "the area particles and their links", "lower --area-particles, --gather-links or --scatter-links");
  AreaParticleOptions ao;
  ao.positions = o.areaParticles;
  ao.sides = o.sides;
  ao.sampling.method = o.pointSampling;
  ao.sampling.seed = particleSeed(o.seed, ParticleStream::Positions);
  AreaParticles area = distributeAreaParticles(scene, ao, &stats);
  const float spacing = area.spacing;
  stats.addDerived("particle_spacing", spacing);
  Stopwatch linkGridClock;
  const float linkRadius = o.linkRadius * spacing;
  const ParticleGrid linkGrid = buildParticleGrid(area.particles, linkRadius);
  stats.addStage("particle_grid", linkGridClock.seconds());
  CatchmentCounters catchments;
  if (o.particleArea == ParticleArea::Catchment) {
    Stopwatch areaClock;
    measureCatchments(scene, area, linkGrid, linkRadius, uint32_t(o.areaSamples),
                      particleSeed(o.seed, ParticleStream::Areas), catchments);
    stats.addStage("particle_areas", areaClock.seconds());
  }
  const std::span<const AreaParticle> particles(area.particles);

  // G2, G3: the links.
  LinkCounters scatterCounters, gatherCounters;
  Stopwatch scatterClock;
  const ParticleLinks scatterLinks =
      buildParticleLinks(scene, vis, particles, linkGrid,
                         {particleSeed(o.seed, ParticleStream::ScatterLinks), uint32_t(o.scatterLinks)}, linkRadius,
                         scatterCounters);
  stats.addStage("scatter_links", scatterClock.seconds());
  report(0.05);
  // G3 (the paper's geometry stage; --geometry frame builds them at the used particles in R3).
  const bool everything = o.geometry == ParticleGeometry::All;
  const LinkDirections gatherDirections{particleSeed(o.seed, ParticleStream::GatherLinks), uint32_t(o.gatherLinks)};
  ParticleLinks gatherLinks;
  if (everything) {
    Stopwatch gatherLinkClock;
    gatherLinks = buildParticleLinks(scene, vis, particles, linkGrid, gatherDirections, linkRadius, gatherCounters);
    stats.addStage("gather_links", gatherLinkClock.seconds());
  }
  report(0.4);

  // G4, G5: radiance particles and their estimation lists (those of the found radiance particles
  // only in R2, with --geometry frame).
  Stopwatch tessellationClock;
  const Tessellation tess = tessellate(scene, o.tessellation * spacing, sides);
  stats.addStage("tessellation", tessellationClock.seconds());
  const float listRadius = o.listRadius * spacing;
  const float listCosine = std::cos(o.listAngle * kPi / 180.0f);
  Stopwatch listGridClock;
  const ParticleGrid listGrid = buildParticleGrid(particles, listRadius);
  stats.addStage("list_grid", listGridClock.seconds());
  EstimationLists lists;
  if (everything) {
    Stopwatch listClock;
    std::vector<uint32_t> all(tess.count);
    std::iota(all.begin(), all.end(), 0u);
    lists = buildEstimationLists(scene, tess, listGrid, listRadius, listCosine, all);
    stats.addStage("estimation_lists", listClock.seconds());
  }
  report(0.5);

  // Lighting stage (4.2): emission, then scattering.
  Stopwatch emissionClock;
  uint64_t shadowRays = 0;
  const std::vector<Rgb> directFlux =
      emitLight(scene, vis, particles, o.emissionSamples, particleSeed(o.seed, ParticleStream::Emission), shadowRays);
  stats.addStage("light_emission", emissionClock.seconds());
  Stopwatch scatteringClock;
  ScatterCounters scattered;
  const std::vector<Rgb> flux = scatterLight(particles, directFlux, scatterLinks, o.bounces,
                                             particleSeed(o.seed, ParticleStream::Scattering), scattered);
  std::vector<Rgb> radiance(particles.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, particles.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) radiance[i] = particleRadiance(particles[i], flux[i]);
  });
  stats.addStage("scattering", scatteringClock.seconds());
  report(0.55);

  // Ray tracing stage (4.3). R1: the camera paths' shading points, and the subtriangles they hit.
  Stopwatch preliminaryClock;
  const EyePaths eye = traceEyePaths(scene, vis, eyePathSettings(o, part));
  const size_t n = eye.points.size();
  std::vector<SubtriangleWeights> around(n);
  std::vector<uint8_t> foundMarks(tess.count, 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1024), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) {
      const ShadingPoint& p = eye.points[i];
      const Vec2 b = barycentricsOf(scene, p.triangle, p.position);
      around[i] = subtriangleAt(tess, p.triangle, sideOf(p, sides), b.x, b.y);
      for (uint32_t id : around[i].ids) std::atomic_ref<uint8_t>(foundMarks[id]).store(1, std::memory_order_relaxed);
    }
  });
  const std::vector<uint32_t> found = markedIndices(foundMarks);
  stats.addStage("preliminary_ray_tracing", preliminaryClock.seconds());
  // The k-th found radiance particle's list.
  if (!everything) {
    Stopwatch listClock;
    lists = buildEstimationLists(scene, tess, listGrid, listRadius, listCosine, found);
    stats.addStage("estimation_lists", listClock.seconds());
  }
  auto listOf = [&](size_t k) { return lists.list(everything ? found[k] : k); };
  // R2: the area particles of their lists.
  std::vector<uint8_t> usedMarks(particles.size(), 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, found.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t k = r.begin(); k != r.end(); ++k)
      for (uint32_t m : listOf(k)) std::atomic_ref<uint8_t>(usedMarks[m]).store(1, std::memory_order_relaxed);
  });
  const std::vector<uint32_t> used = markedIndices(usedMarks);
  report(0.7);

  // R3: gathering at the used area particles (4.3.1): their irradiance from indirect light.
  if (!everything) {
    Stopwatch gatherLinkClock;
    gatherLinks = buildParticleLinks(scene, vis, particles, linkGrid, gatherDirections, linkRadius, gatherCounters, used);
    stats.addStage("gather_links", gatherLinkClock.seconds());
  }
  Stopwatch gatheringClock;
  std::vector<Rgb> gathered(particles.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, used.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t k = r.begin(); k != r.end(); ++k)
      gathered[used[k]] = gatherIrradiance(everything ? gatherLinks.of(used[k]) : gatherLinks.row(k), radiance);
  });
  stats.addStage("gathering", gatheringClock.seconds());

  // R4: radiance estimation at the found radiance particles (4.3.2), as irradiance: the list's
  // gathered flux over the list's area. A radiance particle with an empty list takes the nearest
  // area particle facing its side's way within the list radius (or nothing), and is counted.
  Stopwatch estimationClock;
  std::vector<Rgb> irradiance(tess.count > 0 ? found.size() : 0);
  std::vector<uint32_t> foundSlot(tess.count, kNoParticle);
  for (size_t k = 0; k < found.size(); ++k) foundSlot[found[k]] = uint32_t(k);
  std::atomic<uint64_t> emptyLists{0};
  tbb::parallel_for(tbb::blocked_range<size_t>(0, found.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t k = r.begin(); k != r.end(); ++k) {
      Rgb sum;
      double areaSum = 0;
      for (uint32_t m : listOf(k)) {
        sum += gathered[m] * particles[m].area;
        areaSum += particles[m].area;
      }
      if (areaSum > 0) {
        irradiance[k] = sum / float(areaSum);
      } else {
        ++emptyLists;
        irradiance[k] = Rgb(0.0f);
      }
    }
  });
  stats.addStage("radiance_estimation", estimationClock.seconds());
  report(0.75);

  // R5: the final ray tracing at the shading points: direct light by shadow rays, indirect light
  // interpolated from the three radiance particles around the hit (times the hit's own diffuse
  // reflectance, so that textures stay sharp: README, "Departures").
  Stopwatch tracingClock;
  PointRadiance shading(n);
  estimateDirectLight(scene, vis, eye.points, o.lightSamples, streamSeed(o.seed, RenderStream::Direct), shading.direct,
                      shadowRays);
  std::atomic<uint64_t> glossy{0};
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1024), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) {
      const SubtriangleWeights& w = around[i];
      Rgb e;
      for (int v = 0; v < 3; ++v) e += irradiance[foundSlot[w.ids[v]]] * w.weights[v];
      shading.indirect[i] = eye.points[i].bsdf.kd * e * kInvPi;
      if (eye.points[i].bsdf.type != MaterialType::Diffuse) ++glossy;
    }
  });
  stats.addStage("ray_tracing", tracingClock.seconds());

  if (!dump.empty()) {
    writeDump(dump, "particles.area_particles", "AreaParticle", particles);
    writeDump(dump, "particles.scatter_links", "uint32", std::span(scatterLinks.targets));
    writeDump(dump, "particles.gather_links", "uint32", std::span(gatherLinks.targets));
    writeDump(dump, "particles.gather_link_particles", "uint32", std::span(gatherLinks.rowParticles));
    writeDump(dump, "particles.tessellation", "TriangleTessellation", std::span(tess.triangles));
    writeDump(dump, "particles.list_offsets", "uint64", std::span(lists.offsets));
    writeDump(dump, "particles.list_particles", "uint32", std::span(lists.particles));
    writeDump(dump, "particles.direct_flux", "Rgb", std::span(directFlux));
    writeDump(dump, "particles.flux", "Rgb", std::span(flux));
    writeDump(dump, "particles.radiance", "Rgb", std::span(radiance));
    writeDump(dump, "particles.found_radiance_particles", "uint32", std::span(found));
    writeDump(dump, "particles.used_area_particles", "uint32", std::span(used));
    writeDump(dump, "particles.gathered_irradiance", "Rgb", std::span(gathered));
    writeDump(dump, "particles.radiance_particle_irradiance", "Rgb", std::span(irradiance));
    dumpShadingPoints(dump, "", eye, shading, false);
  }

  shadeImage(out, control, scene, part, eye, shading, {o.layers, false});
  report(1.0);

  stats.addCounter("area_particle_positions", o.areaParticles);
  stats.addCounter("area_samples", catchments.samples);
  stats.addCounter("area_samples_unmatched", catchments.unmatched);
  stats.addCounter("particles_without_area_samples", catchments.empty);
  stats.addCounter("scatter_link_rays", scatterCounters.rays);
  stats.addCounter("scatter_link_misses", scatterCounters.misses);
  stats.addCounter("scatter_links_unmatched", scatterCounters.unmatched);
  stats.addCounter("scatter_link_bytes", scatterLinks.targets.size() * sizeof(uint32_t));
  stats.addCounter("gather_link_rays", gatherCounters.rays);
  stats.addCounter("gather_link_misses", gatherCounters.misses);
  stats.addCounter("gather_links_unmatched", gatherCounters.unmatched);
  stats.addCounter("gather_link_bytes", gatherLinks.targets.size() * sizeof(uint32_t));
  stats.addCounter("radiance_particles", tess.count);
  stats.addCounter("estimation_list_entries", lists.particles.size());
  stats.addCounter("estimation_list_bytes", lists.particles.size() * sizeof(uint32_t) + lists.offsets.size() * sizeof(uint64_t));
  stats.addCounter("lit_particles", scattered.litParticles);
  stats.addCounter("scatter_deposits", scattered.deposits);
  stats.addCounter("scatter_packets_lost", scattered.lost);
  stats.addCounter("found_radiance_particles", found.size());
  stats.addCounter("used_area_particles", used.size());
  stats.addCounter("empty_estimation_lists", emptyLists);
  stats.addCounter("shadow_rays", shadowRays);
  stats.addCounter("eye_rays", eye.rays);
  stats.addCounter("shading_points", n);
  stats.addCounter("glossy_shaded_diffuse", glossy);
  stats.addCounter("invalid_samples", eye.invalid + out.film->droppedPoints());
  return out;
}

}  // namespace lucent
