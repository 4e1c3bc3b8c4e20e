// --method particles: the paper's three stages (Fig. 4). Geometry: area particles, their
// scattering and gathering links, the tessellation into radiance particles and their estimation
// lists. Lighting: emission into the particles, scattering along the links. Ray tracing: camera
// paths through mirrors and glass to shading points (the preliminary ray tracing, whose hits the
// final one reuses), the radiance particles around them and the area particles of their lists,
// gathering at those, radiance estimation at these, and at every shading point direct light by
// shadow rays plus the interpolated indirect light.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <memory>
#include <numeric>
#include <optional>
#include <stdexcept>

#include "lucent/core/parallel.h"
#include "lucent/core/dump.h"
#include "lucent/core/memory.h"
#include "lucent/core/stop.h"
#include "lucent/methods/particles.h"
#include "lucent/pipeline/direct_light.h"
#include "lucent/pipeline/dumps.h"
#include "lucent/pipeline/film.h"
#include "lucent/pipeline/render_driver.h"
#include "lucent/pipeline/shading_points.h"
#include "methods/particles/indirect_field.h"
#include "methods/particles/particle_lighting.h"
#include "methods/particles/particle_links.h"
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

// The paper's stages (Fig. 4), in order, and what they hand on to each other.
class ParticleRender {
 public:
  ParticleRender(const Scene& scene, const Visibility& vis, const ParticleOptions& o, RenderDriver& driver,
                 RenderStats& stats)
      : scene_(scene), vis_(vis), o_(o), driver_(driver), part_(driver.part()), stats_(stats) {}
  ParticleRender(const ParticleRender&) = delete;
  ParticleRender& operator=(const ParticleRender&) = delete;

  // Geometry stage (4.1). G1: area particles; G2, G3: their links (G3 here with --geometry all;
  // --geometry frame builds them at the used particles in R3).
  void placeAreaParticles() {
    const uint64_t scatterPer = uint64_t(o_.scatterLinks) * uint64_t(o_.scatterLinks);
    const uint64_t gatherPer = uint64_t(o_.gatherLinks) * uint64_t(o_.gatherLinks);
    const uint64_t particleCount = uint64_t(o_.areaParticles) * sides_;
    requireMemory(particleCount * (sizeof(AreaParticle) + 4 * (scatterPer + gatherPer) + 6 * sizeof(Rgb) + 16),
                  "the area particles and their links", "lower --area-particles, --gather-links or --scatter-links");
    AreaParticleOptions ao;
    ao.positions = o_.areaParticles;
    ao.sides = o_.sides;
    ao.sampling.method = o_.pointSampling;
    ao.sampling.seed = particleSeed(o_.common.seed, ParticleStream::Positions);
    area_ = distributeAreaParticles(scene_, ao, &stats_);
    spacing_ = area_.spacing;
    stats_.addDerived("particle_spacing", spacing_);
    linkRadius_ = o_.linkRadius * spacing_;
    {
      StageTimer timer(stats_, "particle_grid");
      covered_ = coveredParticles(vis_, area_.particles, spacing_);
      stats_.addCounter("covered_particles", uint64_t(std::count(covered_.begin(), covered_.end(), uint8_t(1))));
      linkGrid_ = buildParticleGrid(area_.particles, linkRadius_, covered_);
    }
    if (o_.particleArea == ParticleArea::Catchment) {
      StageTimer timer(stats_, "particle_areas");
      measureCatchments(scene_, area_, linkGrid_, linkRadius_, uint32_t(o_.areaSamples),
                        particleSeed(o_.common.seed, ParticleStream::Areas), catchments_);
    }
  }

  void buildScatterLinks() {
    StageTimer timer(stats_, "scatter_links");
    scatterLinks_ = buildParticleLinks(scene_, vis_, particles(), linkGrid_,
                                       {particleSeed(o_.common.seed, ParticleStream::ScatterLinks), uint32_t(o_.scatterLinks)},
                                       linkRadius_, scatterCounters_);
  }

  void buildGatherLinks() {
    if (!everything_) return;
    StageTimer timer(stats_, "gather_links");
    gatherLinks_ = buildParticleLinks(scene_, vis_, particles(), linkGrid_, gatherDirections_, linkRadius_, gatherCounters_);
  }

  // G4, G5: radiance particles and their estimation lists (those of the found radiance particles
  // only in R2, with --geometry frame).
  void buildRadianceParticles() {
    {
      StageTimer timer(stats_, "tessellation");
      tess_ = tessellate(scene_, o_.tessellation * spacing_, sides_);
    }
    listRadius_ = o_.listRadius * spacing_;
    listCosine_ = std::cos(o_.listAngle * kPi / 180.0f);
    {
      StageTimer timer(stats_, "list_grid");
      listGrid_ = buildParticleGrid(particles(), listRadius_, covered_);
    }
    if (everything_) {
      StageTimer timer(stats_, "estimation_lists");
      std::vector<uint32_t> all(tess_.count);
      std::iota(all.begin(), all.end(), 0u);
      lists_ = buildEstimationLists(scene_, tess_, listGrid_, listRadius_, listCosine_, all);
    }
  }

  // Lighting stage (4.2): emission, then scattering.
  void light() {
    {
      StageTimer timer(stats_, "light_emission");
      directFlux_ = emitLight(scene_, vis_, particles(), o_.emissionSamples, particleSeed(o_.common.seed, ParticleStream::Emission),
                              shadowRays_);
    }
    StageTimer timer(stats_, "scattering");
    flux_ = scatterLight(particles(), directFlux_, scatterLinks_, o_.bounces,
                         particleSeed(o_.common.seed, ParticleStream::Scattering), scattered_);
    radiance_.resize(particles().size());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, particles().size(), kItemsPerTask), [&](const tbb::blocked_range<size_t>& r) {
      stopPoint();
      for (size_t i = r.begin(); i != r.end(); ++i) radiance_[i] = particleRadiance(particles()[i], flux_[i]);
    });
  }

  // Ray tracing stage (4.3), band by band of rows: the camera paths (the preliminary ray tracing,
  // whose shading points the final ray tracing reuses), R1 to R4 for the particles they newly need
  // (a particle's light does not depend on which band found it), R5, and the band's light into the
  // film (bands of kReusableBandSamples). Alias detection and dumps need the whole image: one band
  // then.
  void traceFrame() {
    IndirectFieldSetup fs;
    fs.scene = &scene_;
    fs.vis = &vis_;
    fs.tessellation = &tess_;
    fs.particles = particles();
    fs.radiance = radiance_;
    fs.linkGrid = &linkGrid_;
    fs.listGrid = &listGrid_;
    fs.gatherDirections = gatherDirections_;
    fs.linkRadius = linkRadius_;
    fs.listRadius = listRadius_;
    fs.listCosine = listCosine_;
    fs.allLists = everything_ ? &lists_ : nullptr;
    fs.allGatherLinks = everything_ ? &gatherLinks_ : nullptr;
    field_.emplace(fs);

    film_ = &driver_.startFilm(Film::Sums::PerPart, {o_.common.layers, false});
    RenderStats frameStages;
    BandLoop loop;
    loop.maxSamples = wholeImage_ ? ~uint64_t(0) : kReusableBandSamples;
    loop.progressFrom = 0.6, loop.progressTo = 0.95;
    const bool finished = driver_.renderBands(loop, [&](const PixelRect& band, size_t, const auto&) {
      EyePathSettings settingsOfBand = eyePathSettings(o_.common, o_.shading.maxSpecularDepth, part_);
      settingsOfBand.region = band;
      beginStage("preliminary_ray_tracing");
      Stopwatch preliminaryClock;
      eye_ = traceEyePaths(scene_, vis_, settingsOfBand);
      frameStages.addStage("preliminary_ray_tracing", preliminaryClock.seconds());
      std::vector<SubtriangleWeights> around(eye_.points.size());
      const FieldUpdate update = field_->add(eye_.points, around, frameStages);
      first_.foundRadianceParticles += update.foundRadianceParticles;
      first_.usedAreaParticles += update.usedAreaParticles;
      shading_ = shade(eye_, around, "", frameStages);
      countPaths(eye_);
      if (!wholeImage_) addToFilm(eye_, shading_);
    });
    if (!finished) throw RenderStopped();
    stats_.addStagesSummed(frameStages);
  }

  // 4.3.3, Table 2(b): adaptive supersampling. Pixels whose neighbours differ from them (alias
  // detection) are traced again with supersample x supersample stratified samples, whose new
  // radiance and area particles are found and gathered, and which replace the pixel's one sample.
  void supersample() {
    if (o_.supersample <= 0) return;
    std::vector<uint8_t> flagged;
    {
      StageTimer timer(stats_, "alias_detection");
      flagged = detectAliases(scene_, eye_, shading_, o_.aliasContrast);
      for (uint8_t f : flagged) aliased_ += f;
    }
    {
      StageTimer timer(stats_, "preliminary_ray_tracing_adaptive");
      EyePathSettings es = eyePathSettings(o_.common, o_.shading.maxSpecularDepth, part_);
      es.spp = o_.supersample * o_.supersample;
      es.sampleBegin = 0;
      es.sampleEnd = es.spp;
      es.pixelMask = flagged;
      extra_ = traceEyePaths(scene_, vis_, es);
    }
    std::vector<SubtriangleWeights> extraAround(extra_.points.size());
    added_ = field_->add(extra_.points, extraAround, stats_, "_adaptive");
    extraShading_ = shade(extra_, extraAround, "_adaptive", stats_);
    countPaths(extra_);
    // The flagged pixels' first samples give way to their supersamples.
    for (size_t i = 0; i < eye_.pixels.size(); ++i)
      if (flagged[i]) {
        eye_.pixels[i] = EyePixel{};
        if (o_.common.layers) eye_.features[i] = EyeFeatures{};
      }
    for (size_t i = 0; i < eye_.points.size(); ++i) {
      const size_t local = size_t(eye_.points[i].pixel % uint32_t(scene_.camera.width) - uint32_t(part_.region.x0)) +
                           size_t(eye_.points[i].pixel / uint32_t(scene_.camera.width) - uint32_t(part_.region.y0)) *
                               size_t(part_.region.width());
      if (flagged[local]) shading_.direct[i] = shading_.indirect[i] = Rgb(0.0f);
    }
  }

  void dumpStages() const {
    const std::string& dump = o_.shading.dumpDirectory;
    if (dump.empty()) return;
    writeDump(dump, "particles.area_particles", "AreaParticle", particles());
    writeDump(dump, "particles.scatter_links", "uint32", std::span(scatterLinks_.targets));
    const ParticleLinks& gl = gatherLinksBuilt();
    writeDump(dump, "particles.gather_links", "uint32", std::span(gl.targets));
    writeDump(dump, "particles.gather_link_particles", "uint32", std::span(gl.rowParticles));
    writeDump(dump, "particles.tessellation", "TriangleTessellation", std::span(tess_.triangles));
    const EstimationLists& ls = listsBuilt();
    writeDump(dump, "particles.list_offsets", "uint64", std::span(ls.offsets));
    writeDump(dump, "particles.list_particles", "uint32", std::span(ls.particles));
    writeDump(dump, "particles.direct_flux", "Rgb", std::span(directFlux_));
    writeDump(dump, "particles.flux", "Rgb", std::span(flux_));
    writeDump(dump, "particles.radiance", "Rgb", std::span(radiance_));
    writeDump(dump, "particles.found_radiance_particles", "uint32", std::span(field_->found()));
    writeDump(dump, "particles.used_area_particles", "uint32", std::span(field_->used()));
    writeDump(dump, "particles.gathered_irradiance", "Rgb", std::span(field_->gathered()));
    writeDump(dump, "particles.radiance_particle_irradiance", "Rgb", std::span(field_->foundIrradiance()));
    dumpShadingPoints(dump, "", eye_, shading_, false);
  }

  void finishImage(RenderOutput& out) {
    if (wholeImage_) {
      addToFilm(eye_, shading_);
      if (o_.supersample > 0) addToFilm(extra_, extraShading_);
    }
    Stopwatch imageClock;
    driver_.finish(out);
    stats_.addStage("image", imageSeconds_ + imageClock.seconds());
  }

  void reportCounters(const RenderOutput& out) {
    const LinkCounters& frameLinks = field_->gatherCounters();
    gatherCounters_.rays += frameLinks.rays;
    gatherCounters_.misses += frameLinks.misses;
    gatherCounters_.unmatched += frameLinks.unmatched;
    stats_.addCounter("area_particle_positions", o_.areaParticles);
    stats_.addCounter("area_samples", catchments_.samples);
    stats_.addCounter("area_samples_unmatched", catchments_.unmatched);
    stats_.addCounter("particles_without_area_samples", catchments_.empty);
    stats_.addCounter("scatter_link_rays", scatterCounters_.rays);
    stats_.addCounter("scatter_link_misses", scatterCounters_.misses);
    stats_.addCounter("scatter_links_unmatched", scatterCounters_.unmatched);
    stats_.addCounter("scatter_link_bytes", scatterLinks_.targets.size() * sizeof(uint32_t));
    stats_.addCounter("gather_link_rays", gatherCounters_.rays);
    stats_.addCounter("gather_link_misses", gatherCounters_.misses);
    stats_.addCounter("gather_links_unmatched", gatherCounters_.unmatched);
    stats_.addCounter("gather_link_bytes", gatherLinksBuilt().targets.size() * sizeof(uint32_t));
    stats_.addCounter("radiance_particles", tess_.count);
    const EstimationLists& ls = listsBuilt();
    stats_.addCounter("estimation_list_entries", ls.particles.size());
    stats_.addCounter("estimation_list_bytes", ls.particles.size() * sizeof(uint32_t) + ls.offsets.size() * sizeof(uint64_t));
    stats_.addCounter("lit_particles", scattered_.litParticles);
    stats_.addCounter("scatter_deposits", scattered_.deposits);
    stats_.addCounter("scatter_packets_lost", scattered_.lost);
    stats_.addCounter("found_radiance_particles", first_.foundRadianceParticles);
    stats_.addCounter("used_area_particles", first_.usedAreaParticles);
    stats_.addCounter("aliased_pixels", aliased_);
    stats_.addCounter("additional_radiance_particles", added_.foundRadianceParticles);
    stats_.addCounter("additional_area_particles", added_.usedAreaParticles);
    stats_.addCounter("empty_estimation_lists", field_->emptyLists());
    stats_.addCounter("shadow_rays", shadowRays_);
    stats_.addCounter("eye_rays", eyeRays_);
    stats_.addCounter("shading_points", shadingPoints_);
    stats_.addCounter("glossy_shaded_diffuse", glossy_);
    stats_.addCounter("invalid_samples", invalidSamples_ + out.film->droppedPoints());
  }

 private:
  std::span<const AreaParticle> particles() const { return area_.particles; }
  const ParticleLinks& gatherLinksBuilt() const { return everything_ ? gatherLinks_ : field_->frameGatherLinks(); }
  const EstimationLists& listsBuilt() const { return everything_ ? lists_ : field_->frameLists(); }

  // R5: the final ray tracing at the shading points: direct light by shadow rays, indirect light
  // interpolated from the three radiance particles around the hit (times the hit's own diffuse
  // reflectance, so that textures stay sharp: README, "Departures").
  PointRadiance shade(const EyePaths& paths, std::span<const SubtriangleWeights> weights, const std::string& suffix,
                      RenderStats& timing) {
    Stopwatch tracingClock;
    PointRadiance shading(paths.points.size());
    estimateDirectLight(scene_, vis_, paths.points, o_.shading.lightSamples, streamSeed(o_.common.seed, RenderStream::Direct),
                        shading.direct, shadowRays_);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, paths.points.size(), 1024), [&](const tbb::blocked_range<size_t>& r) {
      stopPoint();
      for (size_t i = r.begin(); i != r.end(); ++i) {
        shading.indirect[i] = paths.points[i].bsdf.diffuse() * field_->irradiance(weights[i]) * kInvPi;
        if (!paths.points[i].bsdf.onlyDiffuse()) ++glossy_;
      }
    });
    timing.addStage("ray_tracing" + suffix, tracingClock.seconds());
    return shading;
  }

  void addToFilm(const EyePaths& paths, const PointRadiance& light) {
    Stopwatch filmClock;
    addBand(*film_, paths, light, scene_.camera.width, part_);
    imageSeconds_ += filmClock.seconds();
  }

  void countPaths(const EyePaths& paths) {
    eyeRays_ += paths.rays, shadingPoints_ += paths.points.size(), invalidSamples_ += paths.invalid;
  }

  const Scene& scene_;
  const Visibility& vis_;
  const ParticleOptions& o_;
  RenderDriver& driver_;
  const RenderPart& part_;
  RenderStats& stats_;
  const uint32_t sides_ = o_.sides == ParticleSides::Both ? 2 : 1;
  const bool everything_ = o_.geometry == ParticleGeometry::All;
  const bool wholeImage_ = o_.supersample > 0 || !o_.shading.dumpDirectory.empty();
  const LinkDirections gatherDirections_{particleSeed(o_.common.seed, ParticleStream::GatherLinks), uint32_t(o_.gatherLinks)};

  // Geometry.
  AreaParticles area_;
  float spacing_ = 0, linkRadius_ = 0, listRadius_ = 0, listCosine_ = 0;
  std::vector<uint8_t> covered_;  // coveredParticles: in no grid, so in no link's end and no list
  OrientedPointGrid linkGrid_, listGrid_;
  ParticleLinks scatterLinks_, gatherLinks_;
  Tessellation tess_;
  EstimationLists lists_;
  // Lighting.
  std::vector<Rgb> directFlux_, flux_, radiance_;
  // Ray tracing: the frame's (with wholeImage_, the whole image's) paths and light, and the
  // supersamples'.
  std::optional<IndirectField> field_;
  Film* film_ = nullptr;  // the driver's
  EyePaths eye_, extra_;
  PointRadiance shading_{0}, extraShading_{0};
  FieldUpdate first_, added_;
  double imageSeconds_ = 0;

  CatchmentCounters catchments_;
  LinkCounters scatterCounters_, gatherCounters_;
  ScatterCounters scattered_;
  uint64_t shadowRays_ = 0, aliased_ = 0, eyeRays_ = 0, shadingPoints_ = 0, invalidSamples_ = 0;
  std::atomic<uint64_t> glossy_{0};
};

}  // namespace

RenderOutput renderParticles(const Scene& scene, const Visibility& vis, const ParticleOptions& o,
                             const RenderControl& control) {
  RenderDriver driver(particleOptionTable(), o, control, scene, vis, "--method particles renders the image at once");
  if (hasCutOutSurfaces(scene))
    throw std::invalid_argument("--method particles places its area particles on the surfaces, which would cover the holes of '" +
                                scene.sourcePath + "' (glTF alphaMode MASK or BLEND): render it with pt, pmfg or purcell");
  if (o.supersample > 0 && control.isPart())
    throw std::invalid_argument("--supersample decides each pixel from its neighbours, which a part (--crop, "
                                "--samples) does not have: render the whole image");
  RenderOutput out;
  auto report = [&](double fraction) { driver.reportProgress(fraction); };
  ParticleRender render(scene, vis, o, driver, out.stats);
  render.placeAreaParticles();
  render.buildScatterLinks();
  report(0.05);
  render.buildGatherLinks();
  report(0.4);
  render.buildRadianceParticles();
  report(0.5);
  render.light();
  report(0.55);
  render.traceFrame();
  render.supersample();
  render.dumpStages();
  render.finishImage(out);
  report(1.0);
  render.reportCounters(out);
  return out;
}

}  // namespace lucent
