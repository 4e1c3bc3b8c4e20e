#include "methods/particles/indirect_field.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>

#include "lucent/core/stop.h"

#include "methods/particles/particle_lighting.h"

namespace lucent {

namespace {

// The barycentrics (b1, b2) of p in a triangle (p on it, as a hit's position is).
Vec2 barycentricsOf(const Scene& scene, uint32_t tri, Vec3 p) {
  const Vec3 v0 = scene.vertex(tri, 0), e1 = scene.vertex(tri, 1) - v0, e2 = scene.vertex(tri, 2) - v0, d = p - v0;
  const float d00 = dot(e1, e1), d01 = dot(e1, e2), d11 = dot(e2, e2), d20 = dot(d, e1), d21 = dot(d, e2);
  const float den = d00 * d11 - d01 * d01;
  if (!(den > 0)) return {0, 0};
  return {(d11 * d20 - d01 * d21) / den, (d00 * d21 - d01 * d20) / den};
}

// The indices whose mark is set, in index order.
template <class Mark>
std::vector<uint32_t> markedIndices(const std::vector<Mark>& marks, Mark value) {
  std::vector<uint32_t> out;
  for (size_t i = 0; i < marks.size(); ++i)
    if (marks[i] == value) out.push_back(uint32_t(i));
  return out;
}

}  // namespace

IndirectField::IndirectField(const IndirectFieldSetup& setup)
    : setup_(setup),
      slot_(setup.tessellation->count, kNoParticle),
      usedMark_(setup.particles.size(), 0),
      gathered_(setup.particles.size()) {
  lists_.offsets.assign(1, 0);
  links_.strata = setup.gatherDirections.strata;
}

FieldUpdate IndirectField::add(std::span<const ShadingPoint> points, std::span<SubtriangleWeights> around,
                               RenderStats& stats, const std::string& suffix) {
  const Scene& scene = *setup_.scene;
  const Tessellation& tess = *setup_.tessellation;
  // R1: the subtriangle around each point; its radiance particles not found before are marked
  // (kNoParticle - 1 in their slot).
  constexpr uint32_t kNewlyFound = kNoParticle - 1;
  Stopwatch markClock;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, points.size(), 1024), [&](const tbb::blocked_range<size_t>& r) {
    stopPoint();
    for (size_t i = r.begin(); i != r.end(); ++i) {
      const ShadingPoint& p = points[i];
      const Vec2 b = barycentricsOf(scene, p.triangle, p.position);
      const bool back = dot(p.wo, p.geometricNormal) < 0;
      around[i] = subtriangleAt(tess, p.triangle, tess.sides == 2 && back ? 1u : 0u, b.x, b.y);
      // One-sided particles (--sides front) stand for the front alone: a point seen from behind (a
      // wall's inside whose faces point out) has none of its own, and the front's light is not its.
      if (tess.sides == 1 && back) {
        for (float& w : around[i].weights) w = 0;
        continue;
      }
      for (uint32_t id : around[i].ids)
        if (std::atomic_ref<uint32_t>(slot_[id]).load(std::memory_order_relaxed) == kNoParticle)
          std::atomic_ref<uint32_t>(slot_[id]).store(kNewlyFound, std::memory_order_relaxed);
    }
  });
  const std::vector<uint32_t> newlyFound = markedIndices(slot_, kNewlyFound);
  const size_t firstNew = found_.size();
  for (uint32_t id : newlyFound) {
    slot_[id] = uint32_t(found_.size());
    found_.push_back(id);
  }
  stats.addStage("mark_radiance_particles" + suffix, markClock.seconds());

  // G5 where the frame builds it: the new radiance particles' lists, appended.
  if (!setup_.allLists) {
    Stopwatch listClock;
    const EstimationLists more = buildEstimationLists(scene, tess, *setup_.listGrid, setup_.listRadius,
                                                      setup_.listCosine, newlyFound);
    const uint64_t base = lists_.particles.size();
    lists_.particles.insert(lists_.particles.end(), more.particles.begin(), more.particles.end());
    for (size_t k = 1; k < more.offsets.size(); ++k) lists_.offsets.push_back(base + more.offsets[k]);
    stats.addStage("estimation_lists" + suffix, listClock.seconds());
  }

  // R2: the area particles of the new lists not used before.
  Stopwatch usedClock;
  tbb::parallel_for(tbb::blocked_range<size_t>(firstNew, found_.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
    stopPoint();
    for (size_t k = r.begin(); k != r.end(); ++k)
      for (uint32_t m : listOf(k))
        if (std::atomic_ref<uint8_t>(usedMark_[m]).load(std::memory_order_relaxed) == 0)
          std::atomic_ref<uint8_t>(usedMark_[m]).store(2, std::memory_order_relaxed);
  });
  const std::vector<uint32_t> newlyUsed = markedIndices(usedMark_, uint8_t(2));
  for (uint32_t m : newlyUsed) usedMark_[m] = 1;
  stats.addStage("collect_area_particles" + suffix, usedClock.seconds());

  // R3 (4.3.1): gathering at them, over their gathering links (built now where the frame does).
  const size_t firstRow = links_.rowParticles.size();
  if (!setup_.allGatherLinks) {
    Stopwatch linkClock;
    const ParticleLinks more = buildParticleLinks(scene, *setup_.vis, setup_.particles, *setup_.linkGrid,
                                                  setup_.gatherDirections, setup_.linkRadius, linkCounters_, newlyUsed);
    links_.targets.insert(links_.targets.end(), more.targets.begin(), more.targets.end());
    links_.rowParticles.insert(links_.rowParticles.end(), more.rowParticles.begin(), more.rowParticles.end());
    stats.addStage("gather_links" + suffix, linkClock.seconds());
  }
  Stopwatch gatherClock;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, newlyUsed.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
    stopPoint();
    for (size_t k = r.begin(); k != r.end(); ++k) {
      const uint32_t m = newlyUsed[k];
      gathered_[m] = gatherIrradiance(setup_.allGatherLinks ? setup_.allGatherLinks->of(m) : links_.row(firstRow + k),
                                      setup_.radiance);
    }
  });
  used_.insert(used_.end(), newlyUsed.begin(), newlyUsed.end());
  stats.addStage("gathering" + suffix, gatherClock.seconds());

  // R4 (4.3.2): the new radiance particles' irradiance, the list's gathered flux over the list's
  // own area (no boundary bias). An empty list gives none, and is counted.
  Stopwatch estimationClock;
  irradiance_.resize(found_.size());
  std::atomic<uint64_t> empty{0};
  tbb::parallel_for(tbb::blocked_range<size_t>(firstNew, found_.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
    stopPoint();
    for (size_t k = r.begin(); k != r.end(); ++k) {
      Rgb sum;
      double areaSum = 0;
      for (uint32_t m : listOf(k)) {
        sum += gathered_[m] * setup_.particles[m].area;
        areaSum += setup_.particles[m].area;
      }
      empty += !(areaSum > 0);
      irradiance_[k] = areaSum > 0 ? sum / float(areaSum) : Rgb(0.0f);
    }
  });
  emptyLists_ += empty;
  stats.addStage("radiance_estimation" + suffix, estimationClock.seconds());
  return {newlyFound.size(), newlyUsed.size()};
}

}  // namespace lucent
