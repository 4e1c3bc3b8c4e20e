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
#include "lucent/core/stop.h"
#include "lucent/pipeline/direct_light.h"
#include "lucent/pipeline/dumps.h"
#include "lucent/pipeline/film.h"
#include "lucent/pipeline/render_control.h"
#include "lucent/pipeline/shading_points.h"
#include "methods/particles/indirect_field.h"
#include "methods/particles/particle_lighting.h"
#include "methods/particles/particle_links.h"
#include "methods/particles/particles.h"
#include "methods/particles/radiance_particles.h"

namespace lucent {

namespace {

enum class ParticleStream : uint64_t { Positions = 41, ScatterLinks = 42, GatherLinks = 43, Emission = 44, Scattering = 45, Areas = 46 };
uint64_t particleSeed(uint64_t seed, ParticleStream s) { return hashKey(seed, uint64_t(s)); }

// 4.3.3's alias detection, from the single-sample pass (notes A12; the criteria of Jin et al. 2009
// are not in the paper): a pixel is flagged when a 4-neighbour inside the region differs from it in
// the material or the normal (more than 25 degrees) or the distance (by 10%) of the first surface
// its sample shades, in whether it reaches one, or in luminance by a contrast |a - b| / (a + b)
// above `contrast`.
std::vector<uint8_t> detectAliases(const Scene& scene, const EyePaths& eye, const PointRadiance& light, float contrast) {
  const int w = eye.region.width(), h = eye.region.height();
  const size_t n = eye.pixels.size();
  struct PixelKey {
    uint32_t material = kNoParticle;
    Vec3 normal;
    float distance = 0;
    float luminance = 0;
  };
  std::vector<PixelKey> keys(n);
  for (size_t i = 0; i < n; ++i) {
    Rgb emitted;
    for (int c = 0; c < 3; ++c) emitted[c] = float(eye.pixels[i].emitted[c].value());
    keys[i].luminance = emitted.luminance();
  }
  for (size_t k = 0; k < eye.points.size(); ++k) {
    const ShadingPoint& p = eye.points[k];
    const size_t i = size_t(p.pixel / uint32_t(scene.camera.width) - uint32_t(eye.region.y0)) * size_t(w) +
                     size_t(p.pixel % uint32_t(scene.camera.width) - uint32_t(eye.region.x0));
    keys[i].luminance += (p.weight * (light.direct[k] + light.indirect[k])).luminance();
    if (p.branch == 0) {
      keys[i].material = scene.materialIds[p.triangle];
      keys[i].normal = p.normal;
      keys[i].distance = length(p.position - scene.camera.eye);
    }
  }
  const float minCosine = std::cos(25.0f * kPi / 180.0f);
  auto differ = [&](const PixelKey& a, const PixelKey& b) {
    if (a.material != b.material) return true;
    if (a.material != kNoParticle &&
        (dot(a.normal, b.normal) < minCosine || std::max(a.distance, b.distance) > 1.1f * std::min(a.distance, b.distance)))
      return true;
    const float sum = a.luminance + b.luminance;
    return sum > 0 && std::abs(a.luminance - b.luminance) > contrast * sum;
  };
  std::vector<uint8_t> flagged(n, 0);
  tbb::parallel_for(tbb::blocked_range<int>(0, h, 8), [&](const tbb::blocked_range<int>& r) {
    stopPoint();
    for (int y = r.begin(); y != r.end(); ++y)
      for (int x = 0; x < w; ++x) {
        const PixelKey& k = keys[size_t(y) * size_t(w) + size_t(x)];
        bool f = false;
        if (x > 0) f |= differ(k, keys[size_t(y) * size_t(w) + size_t(x - 1)]);
        if (x + 1 < w) f |= differ(k, keys[size_t(y) * size_t(w) + size_t(x + 1)]);
        if (y > 0) f |= differ(k, keys[size_t(y - 1) * size_t(w) + size_t(x)]);
        if (y + 1 < h) f |= differ(k, keys[size_t(y + 1) * size_t(w) + size_t(x)]);
        flagged[size_t(y) * size_t(w) + size_t(x)] = f;
      }
  });
  return flagged;
}

}  // namespace

RenderOutput renderParticles(const Scene& scene, const Visibility& vis, const ParticleOptions& o,
                             const RenderControl& control) {
  const RenderPart part = beginRender(particleOptionTable(), o, control, scene, "--method particles renders the image at once");
  if (o.supersample > 0 && control.isPart())
    throw std::invalid_argument("--supersample decides each pixel from its neighbours, which a part (--crop, "
                                "--samples) does not have: render the whole image");
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
  requireMemory(particleCount * (sizeof(AreaParticle) + 4 * (scatterPer + gatherPer) + 6 * sizeof(Rgb) + 16),
                "the area particles and their links", "lower --area-particles, --gather-links or --scatter-links");
  AreaParticleOptions ao;
  ao.positions = o.areaParticles;
  ao.sides = o.sides;
  ao.sampling.method = o.pointSampling;
  ao.sampling.seed = particleSeed(o.seed, ParticleStream::Positions);
  AreaParticles area = distributeAreaParticles(scene, ao, &stats);
  const float spacing = area.spacing;
  stats.addDerived("particle_spacing", spacing);
  beginStage("particle_grid");
  Stopwatch linkGridClock;
  const float linkRadius = o.linkRadius * spacing;
  const OrientedPointGrid linkGrid = buildParticleGrid(area.particles, linkRadius);
  stats.addStage("particle_grid", linkGridClock.seconds());
  CatchmentCounters catchments;
  if (o.particleArea == ParticleArea::Catchment) {
    beginStage("particle_areas");
    Stopwatch areaClock;
    measureCatchments(scene, area, linkGrid, linkRadius, uint32_t(o.areaSamples),
                      particleSeed(o.seed, ParticleStream::Areas), catchments);
    stats.addStage("particle_areas", areaClock.seconds());
  }
  const std::span<const AreaParticle> particles(area.particles);

  // G2, G3: the links.
  LinkCounters scatterCounters, gatherCounters;
  beginStage("scatter_links");
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
    beginStage("gather_links");
    Stopwatch gatherLinkClock;
    gatherLinks = buildParticleLinks(scene, vis, particles, linkGrid, gatherDirections, linkRadius, gatherCounters);
    stats.addStage("gather_links", gatherLinkClock.seconds());
  }
  report(0.4);

  // G4, G5: radiance particles and their estimation lists (those of the found radiance particles
  // only in R2, with --geometry frame).
  beginStage("tessellation");
  Stopwatch tessellationClock;
  const Tessellation tess = tessellate(scene, o.tessellation * spacing, sides);
  stats.addStage("tessellation", tessellationClock.seconds());
  const float listRadius = o.listRadius * spacing;
  const float listCosine = std::cos(o.listAngle * kPi / 180.0f);
  beginStage("list_grid");
  Stopwatch listGridClock;
  const OrientedPointGrid listGrid = buildParticleGrid(particles, listRadius);
  stats.addStage("list_grid", listGridClock.seconds());
  EstimationLists lists;
  if (everything) {
    beginStage("estimation_lists");
    Stopwatch listClock;
    std::vector<uint32_t> all(tess.count);
    std::iota(all.begin(), all.end(), 0u);
    lists = buildEstimationLists(scene, tess, listGrid, listRadius, listCosine, all);
    stats.addStage("estimation_lists", listClock.seconds());
  }
  report(0.5);

  // Lighting stage (4.2): emission, then scattering.
  beginStage("light_emission");
  Stopwatch emissionClock;
  uint64_t shadowRays = 0;
  const std::vector<Rgb> directFlux =
      emitLight(scene, vis, particles, o.emissionSamples, particleSeed(o.seed, ParticleStream::Emission), shadowRays);
  stats.addStage("light_emission", emissionClock.seconds());
  beginStage("scattering");
  Stopwatch scatteringClock;
  ScatterCounters scattered;
  const std::vector<Rgb> flux = scatterLight(particles, directFlux, scatterLinks, o.bounces,
                                             particleSeed(o.seed, ParticleStream::Scattering), scattered);
  std::vector<Rgb> radiance(particles.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, particles.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    stopPoint();
    for (size_t i = r.begin(); i != r.end(); ++i) radiance[i] = particleRadiance(particles[i], flux[i]);
  });
  stats.addStage("scattering", scatteringClock.seconds());
  report(0.55);

  // Ray tracing stage (4.3): the camera paths (the preliminary ray tracing, whose shading points
  // the final ray tracing reuses), then R1 to R4 for the particles they need.
  IndirectFieldSetup fs;
  fs.scene = &scene;
  fs.vis = &vis;
  fs.tessellation = &tess;
  fs.particles = particles;
  fs.radiance = radiance;
  fs.linkGrid = &linkGrid;
  fs.listGrid = &listGrid;
  fs.gatherDirections = gatherDirections;
  fs.linkRadius = linkRadius;
  fs.listRadius = listRadius;
  fs.listCosine = listCosine;
  fs.allLists = everything ? &lists : nullptr;
  fs.allGatherLinks = everything ? &gatherLinks : nullptr;
  IndirectField field(fs);

  // R5: the final ray tracing at the shading points: direct light by shadow rays, indirect light
  // interpolated from the three radiance particles around the hit (times the hit's own diffuse
  // reflectance, so that textures stay sharp: README, "Departures").
  std::atomic<uint64_t> glossy{0};
  auto shade = [&](const EyePaths& paths, std::span<const SubtriangleWeights> weights, const std::string& suffix,
                   RenderStats& timing) {
    Stopwatch tracingClock;
    PointRadiance shading(paths.points.size());
    estimateDirectLight(scene, vis, paths.points, o.lightSamples, streamSeed(o.seed, RenderStream::Direct),
                        shading.direct, shadowRays);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, paths.points.size(), 1024), [&](const tbb::blocked_range<size_t>& r) {
      stopPoint();
      for (size_t i = r.begin(); i != r.end(); ++i) {
        shading.indirect[i] = paths.points[i].bsdf.kd * field.irradiance(weights[i]) * kInvPi;
        if (paths.points[i].bsdf.type != MaterialType::Diffuse) ++glossy;
      }
    });
    timing.addStage("ray_tracing" + suffix, tracingClock.seconds());
    return shading;
  };

  // The frame band by band of rows: the camera paths (the preliminary ray tracing, whose shading
  // points the final ray tracing reuses), R1 to R4 for the particles they newly need (a particle's
  // light does not depend on which band found it), R5, and the band's light into the film (bands of
  // kReusableBandSamples). Alias detection and dumps need the whole image: one band then.
  auto film = std::make_shared<Film>(startFilm(control, scene, part, Film::Sums::PerPart, {o.layers, false}));
  auto addToFilm = [&](const EyePaths& paths, const PointRadiance& light) {
    Stopwatch filmClock;
    addBand(*film, paths, light, scene.camera.width, part);
    return filmClock.seconds();
  };
  const bool wholeImage = o.supersample > 0 || !dump.empty();
  RenderStats frameStages;
  FieldUpdate first;
  EyePaths eye;  // with wholeImage, the whole image's after the loop
  PointRadiance shading(0);
  double imageSeconds = 0;
  uint64_t eyeRays = 0, shadingPoints = 0, invalidSamples = 0;
  BandLoop loop;
  loop.maxSamples = wholeImage ? ~uint64_t(0) : kReusableBandSamples;
  loop.progressFrom = 0.6, loop.progressTo = 0.95;
  const bool finished = renderRowBands(control, part, loop, *film, [&](const PixelRect& band, size_t, const auto&) {
    EyePathSettings settingsOfBand = eyePathSettings(o, part);
    settingsOfBand.region = band;
    beginStage("preliminary_ray_tracing");
    Stopwatch preliminaryClock;
    eye = traceEyePaths(scene, vis, settingsOfBand);
    frameStages.addStage("preliminary_ray_tracing", preliminaryClock.seconds());
    std::vector<SubtriangleWeights> around(eye.points.size());
    const FieldUpdate update = field.add(eye.points, around, frameStages);
    first.foundRadianceParticles += update.foundRadianceParticles;
    first.usedAreaParticles += update.usedAreaParticles;
    shading = shade(eye, around, "", frameStages);
    eyeRays += eye.rays, shadingPoints += eye.points.size(), invalidSamples += eye.invalid;
    if (!wholeImage) imageSeconds += addToFilm(eye, shading);
  });
  if (!finished) throw RenderStopped();
  stats.addStagesSummed(frameStages);

  // 4.3.3, Table 2(b): adaptive supersampling. Pixels whose neighbours differ from them (alias
  // detection) are traced again with supersample x supersample stratified samples, whose new
  // radiance and area particles are found and gathered, and which replace the pixel's one sample.
  EyePaths extra;
  PointRadiance extraShading(0);
  FieldUpdate added;
  uint64_t aliased = 0;
  if (o.supersample > 0) {
    beginStage("alias_detection");
    Stopwatch detectClock;
    std::vector<uint8_t> flagged = detectAliases(scene, eye, shading, o.aliasContrast);
    for (uint8_t f : flagged) aliased += f;
    stats.addStage("alias_detection", detectClock.seconds());
    beginStage("preliminary_ray_tracing_adaptive");
    Stopwatch adaptiveClock;
    EyePathSettings es = eyePathSettings(o, part);
    es.spp = o.supersample * o.supersample;
    es.sampleBegin = 0;
    es.sampleEnd = es.spp;
    es.pixelMask = flagged;
    extra = traceEyePaths(scene, vis, es);
    stats.addStage("preliminary_ray_tracing_adaptive", adaptiveClock.seconds());
    std::vector<SubtriangleWeights> extraAround(extra.points.size());
    added = field.add(extra.points, extraAround, stats, "_adaptive");
    extraShading = shade(extra, extraAround, "_adaptive", stats);
    eyeRays += extra.rays, shadingPoints += extra.points.size(), invalidSamples += extra.invalid;
    // The flagged pixels' first samples give way to their supersamples.
    for (size_t i = 0; i < eye.pixels.size(); ++i)
      if (flagged[i]) {
        eye.pixels[i] = EyePixel{};
        if (o.layers) eye.features[i] = EyeFeatures{};
      }
    for (size_t i = 0; i < eye.points.size(); ++i) {
      const size_t local = size_t(eye.points[i].pixel % uint32_t(scene.camera.width) - uint32_t(part.region.x0)) +
                           size_t(eye.points[i].pixel / uint32_t(scene.camera.width) - uint32_t(part.region.y0)) *
                               size_t(part.region.width());
      if (flagged[local]) shading.direct[i] = shading.indirect[i] = Rgb(0.0f);
    }
  }

  if (!dump.empty()) {
    writeDump(dump, "particles.area_particles", "AreaParticle", particles);
    writeDump(dump, "particles.scatter_links", "uint32", std::span(scatterLinks.targets));
    const ParticleLinks& gl = everything ? gatherLinks : field.frameGatherLinks();
    writeDump(dump, "particles.gather_links", "uint32", std::span(gl.targets));
    writeDump(dump, "particles.gather_link_particles", "uint32", std::span(gl.rowParticles));
    writeDump(dump, "particles.tessellation", "TriangleTessellation", std::span(tess.triangles));
    const EstimationLists& ls = everything ? lists : field.frameLists();
    writeDump(dump, "particles.list_offsets", "uint64", std::span(ls.offsets));
    writeDump(dump, "particles.list_particles", "uint32", std::span(ls.particles));
    writeDump(dump, "particles.direct_flux", "Rgb", std::span(directFlux));
    writeDump(dump, "particles.flux", "Rgb", std::span(flux));
    writeDump(dump, "particles.radiance", "Rgb", std::span(radiance));
    writeDump(dump, "particles.found_radiance_particles", "uint32", std::span(field.found()));
    writeDump(dump, "particles.used_area_particles", "uint32", std::span(field.used()));
    writeDump(dump, "particles.gathered_irradiance", "Rgb", std::span(field.gathered()));
    writeDump(dump, "particles.radiance_particle_irradiance", "Rgb", std::span(field.foundIrradiance()));
    dumpShadingPoints(dump, "", eye, shading, false);
  }

  if (wholeImage) {
    imageSeconds += addToFilm(eye, shading);
    if (o.supersample > 0) imageSeconds += addToFilm(extra, extraShading);
  }
  Stopwatch imageClock;
  out.image = film->image();
  out.film = film;
  out.sppDone = part.samples();
  stats.addStage("image", imageSeconds + imageClock.seconds());
  report(1.0);

  const LinkCounters& frameLinks = field.gatherCounters();
  gatherCounters.rays += frameLinks.rays;
  gatherCounters.misses += frameLinks.misses;
  gatherCounters.unmatched += frameLinks.unmatched;
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
  stats.addCounter("gather_link_bytes",
                   (everything ? gatherLinks : field.frameGatherLinks()).targets.size() * sizeof(uint32_t));
  stats.addCounter("radiance_particles", tess.count);
  const EstimationLists& listsBuilt = everything ? lists : field.frameLists();
  stats.addCounter("estimation_list_entries", listsBuilt.particles.size());
  stats.addCounter("estimation_list_bytes",
                   listsBuilt.particles.size() * sizeof(uint32_t) + listsBuilt.offsets.size() * sizeof(uint64_t));
  stats.addCounter("lit_particles", scattered.litParticles);
  stats.addCounter("scatter_deposits", scattered.deposits);
  stats.addCounter("scatter_packets_lost", scattered.lost);
  stats.addCounter("found_radiance_particles", first.foundRadianceParticles);
  stats.addCounter("used_area_particles", first.usedAreaParticles);
  stats.addCounter("aliased_pixels", aliased);
  stats.addCounter("additional_radiance_particles", added.foundRadianceParticles);
  stats.addCounter("additional_area_particles", added.usedAreaParticles);
  stats.addCounter("empty_estimation_lists", field.emptyLists());
  stats.addCounter("shadow_rays", shadowRays);
  stats.addCounter("eye_rays", eyeRays);
  stats.addCounter("shading_points", shadingPoints);
  stats.addCounter("glossy_shaded_diffuse", glossy);
  stats.addCounter("invalid_samples", invalidSamples + out.film->droppedPoints());
  return out;
}

}  // namespace lucent
