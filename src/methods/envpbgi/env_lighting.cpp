#include "methods/envpbgi/env_lighting.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <stdexcept>

#include "lucent/core/morton.h"
#include "lucent/core/parallel.h"
#include "lucent/core/stop.h"
#include "lucent/scene/bsdf.h"
#include "lucent/scene/light_sampling.h"
#include "lucent/scene/texture.h"
#include "lucent/techniques/microbuffers/micro_buffer.h"
#include "lucent/techniques/points/bottom_up.h"
#include "lucent/techniques/points/node_tree.h"

namespace lucent {

BufferQuadrature makeQuadrature(MappingKind kind, int side) {
  if (kind == MappingKind::Warped) throw std::invalid_argument("a buffer quadrature needs a fixed mapping");
  BufferQuadrature q;
  q.side = side;
  const MappingTables tables = makeMappingTables(side, 1);
  const SurfaceBsdf white = LambertianLobe{Rgb(1.0f)};
  // Texel centres; a unit diffuse BRDF's weights are cos dOmega / pi.
  evaluatePixels(q.mapping, kind, side, {0.5f, 0.5f}, nullptr, white, {0, 0, 1}, tables);
  q.cosineWeight.assign(q.texels(), 0.0f);
  double sum = 0;
  for (const uint16_t t : q.mapping.used) sum += double(q.mapping.weight[t].r) * kPi;
  const double scale = kPi / sum;
  for (const uint16_t t : q.mapping.used) q.cosineWeight[t] = float(double(q.mapping.weight[t].r) * kPi * scale);
  return q;
}

void renderBuffers(const MicroHierarchy& hierarchy, const MicroRenderSettings& settings, const BufferQuadrature& q,
                   size_t count, const std::function<BufferOrigin(size_t)>& origin, std::span<uint32_t> texels,
                   MicroCounters& counters) {
  struct Scratch {
    std::array<MicroBuffer, kGatherPacket> buffers;
    MicroCounters counters;
  };
  tbb::enumerable_thread_specific<Scratch> scratch;
  // A packet's lanes traverse the hierarchy together, visiting the nodes any of them needs: origins
  // near each other and facing alike share them. The origins are taken by the axis their normal is
  // nearest, then in Morton order of their positions.
  if (count >= (size_t(1) << 31)) throw std::logic_error("renderBuffers: at most 2^31 - 1 buffers at once");
  std::vector<BufferOrigin> origins(count);
  Bounds3 bounds;
  for (size_t k = 0; k < count; ++k) origins[k] = origin(k), bounds.extend(origins[k].position);
  std::vector<uint64_t> order(count);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, count, kItemsPerTask), [&](const tbb::blocked_range<size_t>& r) {
    stopPoint();
    for (size_t k = r.begin(); k != r.end(); ++k)
      order[k] = facingMortonKey(origins[k].position, origins[k].normal, bounds) << 31 | uint64_t(k);
  });
  std::sort(order.begin(), order.end());
  constexpr uint64_t kIndexBits = (uint64_t(1) << 31) - 1;
  const size_t packets = (count + kGatherPacket - 1) / kGatherPacket;
  const size_t side2 = q.texels();
  tbb::parallel_for(tbb::blocked_range<size_t>(0, packets, 1), [&](const tbb::blocked_range<size_t>& r) {
    stopPoint();
    flushDenormals();
    Scratch& s = scratch.local();
    for (size_t packet = r.begin(); packet != r.end(); ++packet) {
      const size_t begin = packet * kGatherPacket, end = std::min(count, begin + kGatherPacket);
      GatherPoint points[kGatherPacket];
      MicroLane lanes[kGatherPacket];
      for (size_t j = begin; j < end; ++j) {
        const BufferOrigin& o = origins[order[j] & kIndexBits];
        GatherPoint& g = points[j - begin];
        g.position = o.position;
        g.frame = Frame(o.normal);
        g.selfDistance = selfIntersectionScale(o.position);
        g.surfaceNormal = o.surfaceNormal;
        lanes[j - begin] = {&g, &q.mapping, &s.buffers[j - begin]};
      }
      renderMicroBuffers(hierarchy, std::span(lanes, end - begin), settings, s.counters);
      for (size_t j = begin; j < end; ++j)
        std::copy_n(s.buffers[j - begin].pixels.begin(), side2, texels.begin() + ptrdiff_t((order[j] & kIndexBits) * side2));
    }
  });
  for (const Scratch& s : scratch) counters += s.counters;
}

BufferIrradiance bufferIrradiance(std::span<const uint32_t> texels, const BufferQuadrature& q, Vec3 normal,
                                  const Environment& environment, std::span<const Rgb> nodeDirect) {
  const Frame frame(normal);
  BufferIrradiance e;
  for (const uint16_t t : q.mapping.used) {
    const uint32_t texel = texels[t];
    if (texel == kEmptyMicroPixel) {
      e.environment += environmentRadiance(environment, frame.toWorld(q.mapping.direction[t])) * q.cosineWeight[t];
    } else if (!nodeDirect.empty() && microPixelShowsNode(texel)) {
      e.nodes += nodeDirect[microPixelNode(texel)] * q.cosineWeight[t];
    }
  }
  return e;
}

Rgb analyticIrradiance(const Scene& scene, const Visibility& vis, Vec3 p, Vec3 n, uint64_t& rays) {
  Rgb sum;
  for (const Light& light : scene.lights) {
    if (!isDeltaLight(light)) continue;
    const LightSample ls = deltaLightSample(light, p);
    const float cosine = dot(n, ls.wi);
    if (!(cosine > 0)) continue;  // also a point at the light itself (NaN)
    ++rays;
    if (!vis.occluded(shadowRay(p, n, ls))) sum += ls.radiance * cosine;
  }
  return sum;
}

void requireEnvironmentLights(const Scene& scene) {
  for (const Light& light : scene.lights)
    if (light.type == LightType::Triangle)
      throw std::invalid_argument(
          "--method envpbgi renders scenes lit by an environment and directional, point or spot lights; '" +
          scene.sourcePath + "' has emitting triangles (render it with pt, pmfg or micro)");
}

void propagateDirectLight(EnvHierarchy& h, std::span<const uint32_t> primary, std::span<Rgb> direct) {
  const uint32_t n = h.leafCount();
  auto has = [&](uint32_t i, uint32_t bits) { return (h.nodes[i].selection & bits) != 0; };
  for (const uint32_t p : primary) h.nodes[p].selection |= kHasDirect;
  points::parallelFor(kRootNode, 2 * n, [&](uint32_t i) {
    if (has(i, kOwnBuffer)) h.nodes[i].selection |= kHasDirect;
  });
  // Downward: a primary point's light to the secondary points below it (3.4's approximation).
  tbb::parallel_for(tbb::blocked_range<size_t>(0, primary.size(), 1), [&](const tbb::blocked_range<size_t>& r) {
    stopPoint();
    for (size_t k = r.begin(); k != r.end(); ++k) {
      const uint32_t p = primary[k];
      for (uint32_t first = firstChild(p), end = first + 2; first < 2 * n; first <<= 1, end <<= 1)
        for (uint32_t i = first; i < end; ++i)
          if (has(i, kSecondary)) direct[i] = direct[p], h.nodes[i].selection |= kHasDirect;
    }
  });
  // Upward: the children's area-weighted mean where the selection found it (3.3), overriding a copy.
  const std::vector<float>& area = h.points.nodeAreas;
  std::vector<uint32_t> arrivals(size_t(2) * n, 0);
  points::parallelFor(n, 2 * n, [&](uint32_t leaf) {
    for (uint32_t i = leaf; i != kRootNode;) {
      const uint32_t p = parentNode(i);
      if (std::atomic_ref<uint32_t>(arrivals[p]).fetch_add(1, std::memory_order_acq_rel) == 0) break;
      // Derivable secondary points, and covered nodes that are not secondary points (those between
      // derivable ones and their sources); never a primary point, which has light of its own (the
      // light copied below it).
      if (has(p, kCovered) && !has(p, kPrimary) && (has(p, kDerivable) || !has(p, kSecondary))) {
        const uint32_t a = firstChild(p), b = secondChild(p);
        const float wa = area[a], wb = area[b];
        direct[p] = wa + wb > 0 ? (direct[a] * wa + direct[b] * wb) / (wa + wb) : (direct[a] + direct[b]) * 0.5f;
        h.nodes[p].selection |= kHasDirect;
      }
      i = p;
    }
  });
}

}  // namespace lucent
