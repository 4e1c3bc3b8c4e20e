// The ray tracing stage's light (4.3.1, 4.3.2): for the shading points a frame reaches, the
// radiance particles around them (found), the area particles of their lists (used), gathering at
// those and radiance estimation at these. Incremental, so that adaptive supersampling's extra
// samples (4.3.3, Table 2(b)) add only the particles they newly need.
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "lucent/core/stats.h"
#include "lucent/pipeline/shading_points.h"
#include "methods/particles/particle_links.h"
#include "methods/particles/radiance_particles.h"

namespace lucent {

struct IndirectFieldSetup {
  const Scene* scene = nullptr;
  const Visibility* vis = nullptr;
  const Tessellation* tessellation = nullptr;
  std::span<const AreaParticle> particles;
  std::span<const Rgb> radiance;  // the area particles' after scattering (4.2.2)
  const OrientedPointGrid* linkGrid = nullptr;
  const OrientedPointGrid* listGrid = nullptr;
  LinkDirections gatherDirections;
  float linkRadius = 0, listRadius = 0, listCosine = 0;
  // --geometry all: every radiance particle's list and every particle's gathering links, built
  // beforehand; otherwise (null) built here as the frame needs them.
  const EstimationLists* allLists = nullptr;
  const ParticleLinks* allGatherLinks = nullptr;
};

// What one update added (Table 2's "found radiance particles", "used area particles").
struct FieldUpdate {
  uint64_t foundRadianceParticles = 0;
  uint64_t usedAreaParticles = 0;
};

class IndirectField {
 public:
  explicit IndirectField(const IndirectFieldSetup& setup);

  // R1's marking (the subtriangles around each point, into `around`), R2, R3 and R4 for the
  // radiance and area particles the points need that no earlier update found. Stages get `suffix`
  // appended (adaptive supersampling's are "_adaptive").
  FieldUpdate add(std::span<const ShadingPoint> points, std::span<SubtriangleWeights> around, RenderStats& stats,
                  const std::string& suffix = "");

  // The interpolated irradiance at a point whose subtriangle `add` found (zero weights: none, and
  // their particles need not have been found).
  Rgb irradiance(const SubtriangleWeights& w) const {
    Rgb e;
    for (int v = 0; v < 3; ++v)
      if (w.weights[v] != 0) e += irradiance_[slot_[w.ids[v]]] * w.weights[v];
    return e;
  }

  const std::vector<uint32_t>& found() const { return found_; }
  const std::vector<uint32_t>& used() const { return used_; }
  const std::vector<Rgb>& gathered() const { return gathered_; }
  const std::vector<Rgb>& foundIrradiance() const { return irradiance_; }
  const EstimationLists& frameLists() const { return lists_; }       // the found ones', in found order
  const ParticleLinks& frameGatherLinks() const { return links_; }   // the used ones', in used order
  const LinkCounters& gatherCounters() const { return linkCounters_; }
  uint64_t emptyLists() const { return emptyLists_; }

 private:
  std::span<const uint32_t> listOf(size_t k) const {
    return setup_.allLists ? setup_.allLists->list(found_[k]) : lists_.list(k);
  }
  IndirectFieldSetup setup_;
  std::vector<uint32_t> slot_;      // per radiance particle: its place in found_, or kNoParticle
  std::vector<uint8_t> usedMark_;   // per area particle
  std::vector<uint32_t> found_, used_;
  std::vector<Rgb> gathered_;       // per area particle: gathered irradiance (used ones only)
  std::vector<Rgb> irradiance_;     // per found radiance particle
  EstimationLists lists_;
  ParticleLinks links_;
  LinkCounters linkCounters_;
  uint64_t emptyLists_ = 0;
};

}  // namespace lucent
