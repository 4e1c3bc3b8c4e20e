// Final gathering at one surface point by micro-rendering: the jittered local frame, the mapping for
// the point's BRDF and view direction, the micro-buffer, and its convolution with the radiance of
// the hierarchy's nodes. Used for the camera's shading points and, with the radiosity lighting, for
// the points of the hierarchy themselves.
#pragma once
#include <span>
#include <vector>

#include "lucent/core/rng.h"
#include "lucent/core/stats.h"
#include "lucent/methods/microrender/hemisphere_mapping.h"
#include "lucent/methods/microrender/micro_rendering.h"

namespace lucent {

// The radiance each node sends towards the gather points: float RGB, and for the packed encoding
// the half floats the paper stores beside the nodes (3.1), which gathering then reads.
struct NodeRadiance {
  std::vector<Rgb> rgb;
  std::vector<HalfRgb> half;
  void finish(NodeEncoding encoding) {
    if (encoding == NodeEncoding::Packed) half = packRadiance(rgb);
  }
};

struct GatherContext {
  const MicroHierarchy* hierarchy = nullptr;
  const MappingTables* tables = nullptr;
  MappingKind mapping = MappingKind::Warped;
  MicroRenderSettings settings;
};

// Per-thread scratch and the stage clocks of the paper's breakdown.
struct GatherScratch {
  HemisphereMapping mapping;
  WarpTable table;
  MicroBuffer buffer;
  MicroCounters counters;
  double buildSeconds = 0;      // tabulating BRDF slices and their inverse CDFs
  double evaluateSeconds = 0;   // the pixels' directions, solid angles and weights
  double rasterizeSeconds = 0;  // traversal and rasterization (ray casting is in counters)
  double convolveSeconds = 0;
};

// A gather point's local frame: the shading normal on +z, turned about it by a random angle ("we
// jitter the local coordinate system slightly at every gather sample", 2.3), and the pixels'
// sample positions jittered together; both from `rng`.
inline GatherPoint jitteredGatherPoint(Vec3 position, Vec3 normal, Rng& rng, Vec2& pixelJitter) {
  GatherPoint g;
  g.position = position;
  const Frame f(normal);
  const float phi = 2.0f * kPi * rng.uniform();
  const float c = std::cos(phi), s = std::sin(phi);
  g.frame = f;
  g.frame.s = f.s * c + f.t * s;
  g.frame.t = f.t * c - f.s * s;
  g.selfDistance = selfIntersectionScale(position);
  pixelJitter = rng.uniform2();
  return g;
}

// Radiance reflected towards wo (world) by a surface point with the given BSDF, gathered from the
// nodes' radiance.
inline Rgb gatherAt(const GatherContext& ctx, Vec3 position, Vec3 normal, Vec3 wo, const SurfaceBsdf& bsdf, Rng& rng,
                    const NodeRadiance& radiance, GatherScratch& s) {
  Vec2 jitter;
  const GatherPoint g = jitteredGatherPoint(position, normal, rng, jitter);
  const Vec3 woLocal = g.frame.toLocal(wo);
  const int side = ctx.tables->bufferSide;
  const Stopwatch buildClock;
  const WarpTable* table = nullptr;
  if (ctx.mapping == MappingKind::Warped) {
    if (bsdf.type == MaterialType::Diffuse) {
      table = &ctx.tables->lambertian;
    } else {
      tabulateBrdfSlice(bsdf, woLocal, *ctx.tables, s.table);
      table = &s.table;
    }
  }
  const double built = buildClock.seconds();
  evaluatePixels(s.mapping, ctx.mapping, side, jitter, table, bsdf, woLocal, *ctx.tables);
  const double evaluated = buildClock.seconds();
  const double rayCastBefore = s.counters.rayCastSeconds;
  renderMicroBuffer(*ctx.hierarchy, g, s.mapping, ctx.settings, s.buffer, s.counters);
  const double rendered = buildClock.seconds();
  const Rgb result = radiance.half.empty() ? convolveMicroBuffer(s.buffer, s.mapping, radiance.rgb)
                                           : convolveMicroBuffer(s.buffer, s.mapping, radiance.half);
  const double done = buildClock.seconds();
  s.buildSeconds += built;
  s.evaluateSeconds += evaluated - built;
  s.rasterizeSeconds += (rendered - evaluated) - (s.counters.rayCastSeconds - rayCastBefore);
  s.convolveSeconds += done - rendered;
  return result;
}

}  // namespace lucent
