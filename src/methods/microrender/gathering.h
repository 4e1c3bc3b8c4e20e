// Final gathering at surface points by micro-rendering, a packet of them at a time: the jittered
// local frame, the mapping for each point's BRDF and view direction, the micro-buffer, and its
// convolution with the radiance of the hierarchy's nodes. Used for the camera's shading points and,
// with the radiosity lighting, for the points of the hierarchy themselves.
#pragma once
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <span>
#include <vector>

#include "lucent/core/parallel.h"
#include "lucent/core/rng.h"
#include "lucent/core/stats.h"
#include "lucent/core/stop.h"
#include "lucent/techniques/microbuffers/hemisphere_mapping.h"
#include "lucent/techniques/microbuffers/micro_rendering.h"

namespace lucent {

// The radiance each node sends towards the gather points: float RGB, for the packed encoding the
// half floats the paper stores beside the nodes (3.1), which gathering then reads, and with
// directional node radiance the interior nodes' DirectionalRadiance. finish() derives the last two
// from `rgb` once it holds every node's radiance.
struct NodeRadiance {
  NodeRadianceKind kind = NodeRadianceKind::Isotropic;  // the renderer's default: MicroRenderOptions::nodeRadiance
  std::vector<Rgb> rgb;
  std::vector<HalfRgb> half;
  std::vector<DirectionalRadiance> directional;
  void finish(const PointHierarchy& h) {
    if (h.encoding == NodeEncoding::Packed) half = packRadiance(rgb);
    if (kind == NodeRadianceKind::Directional) directional = directionalRadiance(h, rgb);
  }
};

struct GatherContext {
  const MicroHierarchy* hierarchy = nullptr;
  const MappingTables* tables = nullptr;
  MappingKind mapping = MappingKind::Warped;
  MicroRenderSettings settings;
};

// One lane of a packet: its gather point, table, mapping and micro-buffer, reused from one packet
// to the next.
struct GatherLane {
  GatherPoint point;
  SurfaceBsdf bsdf;  // the request's, in the point's jittered frame
  HemisphereMapping mapping;
  WarpTable table;
  MicroBuffer buffer;
};

// Per-thread scratch and the stage clocks of the paper's breakdown.
struct GatherScratch {
  std::array<GatherLane, kGatherPacket> lanes;
  MicroCounters counters;
  double buildSeconds = 0;      // tabulating BRDF slices and their inverse CDFs
  double evaluateSeconds = 0;   // the pixels' directions, solid angles and weights
  double rasterizeSeconds = 0;  // traversal and rasterization (ray casting is in counters)
  double convolveSeconds = 0;
};

// A gather point's local frame: the shading normal on +z, turned about it by a random angle ("we
// jitter the local coordinate system slightly at every gather sample", 2.3), and the pixels'
// sample positions jittered together; both from `rng`. surfaceNormal: GatherPoint's.
inline GatherPoint jitteredGatherPoint(Vec3 position, Vec3 normal, Vec3 surfaceNormal, Rng& rng, Vec2& pixelJitter) {
  GatherPoint g;
  g.position = position;
  g.surfaceNormal = surfaceNormal;
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

// A surface point to gather at: reflected radiance towards wo (world), for the given BSDF (in the
// frame Frame(normal), as ShadingPoint's), about the shading normal `normal`, cut by the geometric
// surface (surfaceNormal, GatherPoint's); the frame's and pixels' jitter drawn from rng.
struct GatherRequest {
  Vec3 position, normal, surfaceNormal, wo;
  const SurfaceBsdf* bsdf = nullptr;
  Rng* rng = nullptr;
};

// Gathers at up to kGatherPacket points with one traversal of the hierarchy (renderMicroBuffers):
// each result is what the point would gather alone.
inline void gatherPacket(const GatherContext& ctx, std::span<const GatherRequest> requests,
                         const NodeRadiance& radiance, GatherScratch& s, Rgb* results) {
  const int side = ctx.tables->bufferSide;
  MicroLane lanes[kGatherPacket];
  for (size_t l = 0; l < requests.size(); ++l) {
    const GatherRequest& q = requests[l];
    GatherLane& lane = s.lanes[l];
    Vec2 jitter;
    lane.point = jitteredGatherPoint(q.position, q.normal, q.surfaceNormal, *q.rng, jitter);
    const Vec3 woLocal = lane.point.frame.toLocal(q.wo);
    lane.bsdf = q.bsdf->reframed(Frame(q.normal), lane.point.frame);
    const Stopwatch buildClock;
    const WarpTable* table = nullptr;
    if (ctx.mapping == MappingKind::Warped) {
      if (lane.bsdf.onlyDiffuse()) {
        table = &ctx.tables->lambertian;
      } else {
        tabulateBrdfSlice(lane.bsdf, woLocal, *ctx.tables, lane.table);
        table = &lane.table;
      }
    }
    const double built = buildClock.seconds();
    evaluatePixels(lane.mapping, ctx.mapping, side, jitter, table, lane.bsdf, woLocal, *ctx.tables);
    s.buildSeconds += built;
    s.evaluateSeconds += buildClock.seconds() - built;
    lanes[l] = {&lane.point, &lane.mapping, &lane.buffer};
  }
  const Stopwatch renderClock;
  const double rayCastBefore = s.counters.rayCastSeconds;
  renderMicroBuffers(*ctx.hierarchy, std::span(lanes, requests.size()), ctx.settings, s.counters);
  s.rasterizeSeconds += renderClock.seconds() - (s.counters.rayCastSeconds - rayCastBefore);
  const Stopwatch convolveClock;
  for (size_t l = 0; l < requests.size(); ++l) {
    const GatherLane& lane = s.lanes[l];
    results[l] = radiance.half.empty()
                     ? convolveMicroBuffer(lane.buffer, lane.mapping, radiance.rgb, radiance.directional)
                     : convolveMicroBuffer(lane.buffer, lane.mapping, radiance.half, radiance.directional);
  }
  s.convolveSeconds += convolveClock.seconds();
}

// Gathers at points 0 .. count - 1 in packets of kGatherPacket consecutive points (the paper's warp
// of neighbouring gather points, 3.2), in parallel, two packets per task: a packet is a whole
// traversal, and a coarser grain would leave the few packets of a radiosity level to one thread.
// request(k, rng) seeds rng and returns point k's request (which points to rng); deliver(k, result)
// takes its result; finished(points) follows each task with the number of points it gathered. A
// point's result does not depend on its packet, its task or its thread.
template <class Request, class Deliver, class Finished>
void gatherInPackets(const GatherContext& ctx, size_t count, const NodeRadiance& radiance,
                     tbb::enumerable_thread_specific<GatherScratch>& scratch, Request&& request, Deliver&& deliver,
                     Finished&& finished) {
  const size_t packets = (count + kGatherPacket - 1) / kGatherPacket;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, packets, 2), [&](const tbb::blocked_range<size_t>& r) {
    stopPoint();
    flushDenormals();  // every thread computes alike, whoever created it
    GatherScratch& s = scratch.local();
    size_t gathered = 0;
    for (size_t packet = r.begin(); packet != r.end(); ++packet) {
      const size_t begin = packet * kGatherPacket, end = std::min(count, begin + kGatherPacket);
      Rng rngs[kGatherPacket];
      GatherRequest requests[kGatherPacket];
      for (size_t k = begin; k < end; ++k) requests[k - begin] = request(k, rngs[k - begin]);
      Rgb results[kGatherPacket];
      gatherPacket(ctx, std::span(requests, end - begin), radiance, s, results);
      for (size_t k = begin; k < end; ++k) deliver(k, results[k - begin]);
      gathered += end - begin;
    }
    finished(gathered);
  });
}

// One point: a packet of one.
inline Rgb gatherAt(const GatherContext& ctx, Vec3 position, Vec3 normal, Vec3 surfaceNormal, Vec3 wo,
                    const SurfaceBsdf& bsdf, Rng& rng, const NodeRadiance& radiance, GatherScratch& s) {
  const GatherRequest request{position, normal, surfaceNormal, wo, &bsdf, &rng};
  Rgb result;
  gatherPacket(ctx, std::span(&request, 1), radiance, s, &result);
  return result;
}

}  // namespace lucent
