// One gather point's micro-rendering (Ritschel et al. 2009, 2.2): the cut by depth-first traversal
// with computed skip pointers (2.1, 3.1), rasterization with a depth test, on-demand ray casting of
// the post-traversal list, and the convolution. One template per node encoding, no virtual calls.
#include "lucent/methods/microrender/micro_rendering.h"

#include <bit>
#include <cmath>

#include "lucent/core/stats.h"

namespace lucent {

namespace {

// Slope (rise over run) below which a node lying along the receiver's tangent plane is dropped:
// 0.6 degrees.
constexpr float kHorizonSlope = 0.01f;

struct FloatNodes {
  const TraversalNode* nodes;
  TraversalNode operator()(uint32_t i) const { return nodes[i]; }
};

struct PackedNodes {
  const PackedNode* nodes;
  NodeQuantization quantization;
  const float* coneSin;
  const float* coneCos;
  TraversalNode operator()(uint32_t i) const {
    const PackedNode& p = nodes[i];
    const uint32_t code = coneCode(p);
    return {decodeCenter(p, quantization), decodeRadius(p, quantization), decodeNormal(p), coneSin[code], coneCos[code]};
  }
};

// Largest cosine between the direction w and a normal of the cone (axis, angle beta).
inline float bestFacingCosine(const TraversalNode& node, float cosToAxis) {
  if (cosToAxis >= node.coneCos) return 1.0f;
  const float sinToAxis = std::sqrt(std::max(0.0f, 1.0f - cosToAxis * cosToAxis));
  return cosToAxis * node.coneCos + sinToAxis * node.coneSin;  // cos(angle - beta)
}

// One listed disc against every pixel's ray: the innermost loop of ray casting, over structure of
// arrays with selects, so that it vectorizes; an AVX2 clone is picked at run time where the CPU has
// it (the same IEEE operations, so the same results: no FMA contraction, -ffp-contract=off).
// Rays are cast in tiles of kRayTile x kRayTile pixels, each bounded by a cone of directions.
constexpr int kRayTile = 4;
constexpr int kMaxRayTiles = (kMaxMicroBufferSide + kRayTile - 1) / kRayTile * ((kMaxMicroBufferSide + kRayTile - 1) / kRayTile);
static_assert(kMaxRayTiles <= 64, "reached tiles are a 64-bit mask");

struct DiscForRays {
  float px, py, pz;  // gather point minus disc centre
  float ax, ay, az;  // disc normal
  float height;      // of the gather point above the disc's plane
  float radius2, tMin;
};
__attribute__((target_clones("avx2", "default"))) void intersectDisc(
    const DiscForRays disc, uint32_t index, const float* dx, const float* dy, const float* dz, size_t count,
    float* nearestT, uint32_t* nearestNode) {
  for (size_t k = 0; k < count; ++k) {
    const float cosine = dx[k] * disc.ax + dy[k] * disc.ay + dz[k] * disc.az;  // < 0 towards the disc
    const float t = disc.height / -cosine;
    const float qx = disc.px + t * dx[k], qy = disc.py + t * dy[k], qz = disc.pz + t * dz[k];
    const bool hit = (cosine < 0) & (t > disc.tMin) & (t < nearestT[k]) & (qx * qx + qy * qy + qz * qz <= disc.radius2);
    nearestT[k] = hit ? t : nearestT[k];
    nearestNode[k] = hit ? index : nearestNode[k];
  }
}

template <class Nodes>
class MicroRasterizer {
 public:
  MicroRasterizer(const Nodes& nodes, const float* areas, const float* thickness, uint32_t leafCount,
                  const GatherPoint& gather, const HemisphereMapping& mapping, const MicroRenderSettings& settings,
                  MicroBuffer& buffer, MicroCounters& counters)
      : nodes_(nodes), areas_(areas), thickness_(thickness), leafCount_(leafCount), g_(gather), m_(mapping),
        s_(settings), b_(buffer), c_(counters) {}

  void run() {
    b_.pixels.assign(size_t(m_.width) * m_.height, kEmptyMicroPixel);
    for (size_t p = 0; p < m_.direction.size(); ++p) b_.worldDirection[p] = g_.frame.toWorld(m_.direction[p]);
    b_.listed = 0;
    raysReady_ = false;
    ++c_.buffers;
    traverse();
    if (b_.listed > 0) castRays();
    c_.buffersRayCast += listedAny_;
  }

 private:
  // 2.2 "Point Hierarchy Cut": depth first from the root; a node goes to the buffer when it subtends
  // no more than its pixel's solid angle, otherwise its children are visited; leaves larger than a
  // pixel go to the post-traversal list. Skip pointers are computed (node_tree.h).
  void traverse() {
    const Vec3 p = g_.position, normal = g_.frame.n;
    uint32_t i = kRootNode;
    while (i != kTraversalEnd) {
      ++c_.nodesVisited;
      const TraversalNode node = nodes_(i);
      const bool leaf = isLeafNode(i, leafCount_);
      const Vec3 v = node.center - p;
      const float height = dot(v, normal);
      // Below the tangent plane altogether.
      if (height <= -node.radius) {
        i = nextNodeSkippingSubtree(i);
        continue;
      }
      const float d2 = dot(v, v);
      const float d = std::sqrt(d2);
      const float invD = d > 0 ? 1.0f / d : 0.0f;
      const float cosToAxis = -dot(node.axis, v) * invD;  // axis against the direction to p
      float solidAngle;
      if (leaf) {
        // A leaf is a disc in its triangle's plane: it faces p exactly when p lies in front of the
        // plane. coneSin is the slack of a quantized normal (0 for float nodes).
        const float facing = -dot(node.axis, v);
        if (facing <= d * node.coneSin + g_.selfDistance) {
          i = nextNodeSkippingSubtree(i);
          continue;
        }
        solidAngle = kPi * node.radius * node.radius * facing / (d2 * d);  // projected disc
      } else {
        if (d <= node.radius) {
          i = firstChild(i);
          continue;
        }
        // Back-face culling with the normal cone: from points of the sphere, p is seen within
        // alpha = asin(r / d) of the centre's direction; no normal of the cone can face it when the
        // axis is more than 90 degrees + alpha + beta away from that direction.
        const float sinA = node.radius * invD, cosA = std::sqrt(std::max(0.0f, 1.0f - sinA * sinA));
        if (cosA * node.coneCos - sinA * node.coneSin > 0 && cosToAxis < -(sinA * node.coneCos + cosA * node.coneSin)) {
          i = nextNodeSkippingSubtree(i);
          continue;
        }
        // Coplanar culling: a flat node lying in the receiver's tangent plane (the receiver's own
        // floor or wall) is seen, if at all, within kHorizonSlope of the horizon. Its leaves would be
        // culled one by one (their planes pass through the receiver); this stops the descent early.
        // The leaves' planes are tilted from the tangent plane by at most the cone's angle plus the
        // axis's tilt; within the sphere they rise at most r sin(tilt) above the centre's height.
        const float horizon = g_.selfDistance + kHorizonSlope * (d - node.radius);
        if (std::abs(height) <= horizon) {
          const float cosTilt = std::abs(dot(node.axis, normal));
          const float sinTilt = std::sqrt(std::max(0.0f, 1.0f - cosTilt * cosTilt));
          const float cosAll = cosTilt * node.coneCos - sinTilt * node.coneSin;  // cos(tilt + beta)
          const float sinAll = cosAll > 0 ? node.coneSin * cosTilt + node.coneCos * sinTilt : 1.0f;
          if (std::abs(height) + node.radius * sinAll <= horizon) {
            i = nextNodeSkippingSubtree(i);
            continue;
          }
        }
        // What the node's surface subtends: its area seen at the best cosine its cone allows. The
        // sphere's cap (QSplat's measure) is 1.5 to 3 times that for flat nodes and made the cut's
        // nodes a third of a pixel; the spacing bound below keeps the sphere within a pixel's reach.
        solidAngle = std::min(2.0f * kPi * (1.0f - cosA), areas_[i] * bestFacingCosine(node, cosToAxis) * invD * invD);
      }
      const Vec3 local = g_.frame.toLocal(v * invD);
      const int pixel = m_.pixelOf(local);
      // Larger than its pixel (the paper's solid-angle criterion), or wider than the pixel spacing
      // (see HemisphereMapping::spacing): refine.
      if (solidAngle > m_.solidAngle[size_t(pixel)] || node.radius > d * m_.spacing[size_t(pixel)]) {
        if (!leaf) {
          i = firstChild(i);
        } else {
          if (s_.rayCasting) listLeaf(i); else splat(pixel, node, v, local, d, i);
          i = nextNodeSkippingSubtree(i);
        }
        continue;
      }
      // At most a pixel: rasterize, unless the centre lies in the tangent plane or below it (nodes of
      // the receiver's own plane straddle it: no ray from the receiver meets them) or no normal of the
      // cone faces the receiver.
      if (local.z * d > g_.selfDistance && bestFacingCosine(node, cosToAxis) > 0) splat(pixel, node, v, local, d, i);
      i = nextNodeSkippingSubtree(i);
    }
  }

  // A node of at most a pixel's solid angle goes to the pixels of its 3 x 3 neighbourhood whose
  // sample ray meets it: a leaf's disc (one-sided), an interior node's sphere within its slab
  // (MicroHierarchy::thickness). Nodes at the threshold are up to a pixel wide, so the centre's
  // pixel alone would leave holes that let the background through (about 2% of the pixels); the
  // bounding sphere alone would widen every silhouette by up to a pixel, showing near surfaces
  // in front of far ones or of the open sky (on the Cornell box, 10% more indirect light).
  void splat(int pixel, const TraversalNode& node, Vec3 toCentre, Vec3 local, float distance, uint32_t index) {
    ++c_.nodesSplatted;
    // First the bounding sphere's cone, in the local frame (one dot product), then the exact test.
    const float sinRadius = node.radius / distance;
    const float cosRadius = std::sqrt(std::max(0.0f, 1.0f - sinRadius * sinRadius));
    const uint32_t packed = packMicroPixel(s_.depth.code(distance), index);
    const Vec3 pc = -toCentre;  // gather point minus node centre
    const float height = dot(pc, node.axis), r2 = node.radius * node.radius, pc2 = dot(pc, pc);
    const bool leaf = index >= leafCount_;
    const float thickness = thickness_[index];
    const bool flat = thickness < node.radius;  // else the slab cuts nothing off the sphere
    const int w = m_.width, h = m_.height, x = pixel % w, y = pixel / w;
    // The tests are multiplied through by cosine^2 (no division per pixel).
    for (int yy = std::max(0, y - 1); yy <= std::min(h - 1, y + 1); ++yy)
      for (int xx = std::max(0, x - 1); xx <= std::min(w - 1, x + 1); ++xx) {
        const int p = yy * w + xx;
        if (dot(m_.direction[size_t(p)], local) < cosRadius) continue;  // also unused pixels: (0, 0, 0)
        const Vec3 dir = b_.worldDirection[size_t(p)];
        const float cosine = dot(dir, node.axis), b = dot(pc, dir), cos2 = cosine * cosine;
        if (leaf) {
          // The ray meets the disc's plane at t = height / -cosine, beyond the receiver's own
          // surface, within the radius: |pc cosine - dir height| <= r |cosine|.
          if (!(cosine < 0) || !(height > -g_.selfDistance * cosine)) continue;
          const Vec3 q = pc * cosine - dir * height;
          if (dot(q, q) > r2 * cos2) continue;
        } else {
          // |pc + t dir|^2 = pc2 + 2 b t + t^2 is least at t = -b (the ray meets the sphere: the
          // cone test), and over the slab's stretch of the ray at t = -b if the slab holds that
          // point, else at the slab's face nearer to it, where t cosine = e.
          const float g = height - b * cosine;  // signed distance from the plane at t = -b
          if (flat && std::abs(g) > thickness) {
            const float e = std::copysign(thickness, g) - height;
            if (cos2 * pc2 + 2 * b * cosine * e + e * e > r2 * cos2) continue;
          }
        }
        uint32_t& px = b_.pixels[size_t(p)];
        px = std::min(px, packed);
      }
  }

  void listLeaf(uint32_t node) {
    if (b_.listed == b_.postTraversal.size()) {
      ++c_.listFlushes;
      castRays();
    }
    b_.postTraversal[b_.listed++] = node;
    ++c_.leavesListed;
    listedAny_ = true;
  }

  // The rays of the used pixels, tile by tile, and each tile's bounding cone of directions.
  void prepareRays() {
    const int tilesX = (m_.width + kRayTile - 1) / kRayTile, tilesY = (m_.height + kRayTile - 1) / kRayTile;
    uint32_t k = 0, tile = 0;
    for (int ty = 0; ty < tilesY; ++ty)
      for (int tx = 0; tx < tilesX; ++tx, ++tile) {
        b_.tileBegin[tile] = k;
        Vec3 sum;
        for (int y = ty * kRayTile; y < std::min(m_.height, (ty + 1) * kRayTile); ++y)
          for (int x = tx * kRayTile; x < std::min(m_.width, (tx + 1) * kRayTile); ++x) {
            const int pixel = y * m_.width + x;
            if (m_.direction[size_t(pixel)] == Vec3{}) continue;  // unused: no direction
            const Vec3 w = b_.worldDirection[size_t(pixel)];
            b_.dirX[k] = w.x, b_.dirY[k] = w.y, b_.dirZ[k] = w.z;
            b_.rayPixel[k++] = uint16_t(pixel);
            sum += w;
          }
        const float len = length(sum);
        const Vec3 axis = len > 0 ? sum / len : Vec3{0, 0, 1};
        float cosCone = 1;
        for (uint32_t r = b_.tileBegin[tile]; r < k; ++r)
          cosCone = std::min(cosCone, axis.x * b_.dirX[r] + axis.y * b_.dirY[r] + axis.z * b_.dirZ[r]);
        cosCone = std::max(-1.0f, cosCone - 1e-5f);  // rounding margin
        b_.tileAxisX[tile] = axis.x, b_.tileAxisY[tile] = axis.y, b_.tileAxisZ[tile] = axis.z;
        b_.tileCos[tile] = cosCone;
        b_.tileSin[tile] = std::sqrt(std::max(0.0f, 1.0f - cosCone * cosCone));
      }
    b_.tileBegin[tile] = k;
    rayCount_ = k;
    tileCount_ = tile;
    raysReady_ = true;
  }

  // The tiles whose cone of directions (half-angle beta) reaches the cone of half-angle alpha about
  // toDisc: those whose axis lies within alpha + beta of it (all when alpha + beta reaches pi).
  uint64_t tilesReached(float sinA, Vec3 toDisc) const {
    const float cosA = std::sqrt(1 - sinA * sinA);
    // Two passes, the first without branches so that it vectorizes.
    int32_t flags[kMaxRayTiles];
    for (uint32_t tile = 0; tile < tileCount_; ++tile) {
      const float cosB = b_.tileCos[tile], sinB = b_.tileSin[tile];
      const float cosAB = cosA * cosB - sinA * sinB;
      const bool beyondPi = (sinA * cosB + cosA * sinB < 0) & (cosAB < 0);
      const float axisDot = b_.tileAxisX[tile] * toDisc.x + b_.tileAxisY[tile] * toDisc.y + b_.tileAxisZ[tile] * toDisc.z;
      flags[tile] = beyondPi | (axisDot >= cosAB - 1e-5f);
    }
    uint64_t reached = 0;
    for (uint32_t tile = 0; tile < tileCount_; ++tile) reached |= uint64_t(flags[tile]) << tile;
    return reached;
  }

  // 2.2 "On-demand Ray Casting": one ray per used pixel, in the pixel's direction, against every
  // listed disc; the nearest hit enters the buffer through the same depth test as the splats. The
  // loop over pixels is innermost so that it vectorizes (structure of arrays, selects, no branches).
  // A disc is tested against the rays of the tiles whose cone of directions reaches the cone the
  // disc subtends: the same hits as testing every ray (every listed disc meets a ray in list order).
  void castRays() {
    const Stopwatch clock;
    if (!raysReady_) prepareRays();
    const size_t used = rayCount_;
    float* nearestT = b_.nearestT.data();
    uint32_t* nearestNode = b_.nearestNode.data();
    const float* dx = b_.dirX.data();
    const float* dy = b_.dirY.data();
    const float* dz = b_.dirZ.data();
    for (size_t k = 0; k < used; ++k) nearestT[k] = kInf, nearestNode[k] = 0;
    const float tMin = g_.selfDistance;
    for (uint32_t j = 0; j < b_.listed; ++j) {
      const uint32_t index = b_.postTraversal[j];
      const TraversalNode disc = nodes_(index);
      const Vec3 pc = g_.position - disc.center;
      const float ax = disc.axis.x, ay = disc.axis.y, az = disc.axis.z;
      const float height = dot(pc, disc.axis);  // > 0: p in front of the disc
      const float r2 = disc.radius * disc.radius;
      const DiscForRays rays{pc.x, pc.y, pc.z, ax, ay, az, height, r2, tMin};
      // The disc lies within its bounding sphere, which subtends a cone of half-angle alpha about
      // the direction to its centre; a tile whose cone (half-angle beta) is further than alpha + beta
      // from it has no ray that can hit the disc.
      const float d = length(pc);
      const float sinA = disc.radius * 1.0001f / d;
      if (!(sinA < 1)) {
        intersectDisc(rays, index, dx, dy, dz, used, nearestT, nearestNode);
        c_.rayDiscTests += used;
        continue;
      }
      // Consecutive tiles hold consecutive rays: each run of reached tiles is one call.
      uint64_t reached = tilesReached(sinA, pc * (-1.0f / d));
      while (reached) {
        const uint32_t first = uint32_t(std::countr_zero(reached));
        const uint32_t end = first + uint32_t(std::countr_one(reached >> first));
        reached = end < 64 ? reached & (~uint64_t(0) << end) : 0;
        const uint32_t begin = b_.tileBegin[first], count = b_.tileBegin[end] - begin;
        if (count == 0) continue;
        intersectDisc(rays, index, dx + begin, dy + begin, dz + begin, count, nearestT + begin, nearestNode + begin);
        c_.rayDiscTests += count;
      }
    }
    for (size_t k = 0; k < used; ++k)
      if (nearestT[k] < kInf) {
        uint32_t& px = b_.pixels[b_.rayPixel[k]];
        px = std::min(px, packMicroPixel(s_.depth.code(nearestT[k]), nearestNode[k]));
      }
    b_.listed = 0;
    c_.rayCastSeconds += clock.seconds();
  }

  const Nodes& nodes_;
  const float* areas_;      // surface area each node stands for
  const float* thickness_;  // MicroHierarchy::thickness
  uint32_t leafCount_;
  const GatherPoint& g_;
  const HemisphereMapping& m_;
  const MicroRenderSettings& s_;
  MicroBuffer& b_;
  MicroCounters& c_;
  bool raysReady_ = false, listedAny_ = false;
  uint32_t rayCount_ = 0, tileCount_ = 0;
};

template <class Radiance>
Rgb convolve(const MicroBuffer& b, const HemisphereMapping& m, Radiance radiance) {
  Rgb sum;
  for (const uint16_t k : m.used) {
    const uint32_t px = b.pixels[k];
    if (px != kEmptyMicroPixel) sum += radiance(microPixelNode(px)) * m.weight[k];
  }
  return sum;
}

}  // namespace

void MicroBuffer::resize(int bufferSide) {
  side = bufferSide;
  const size_t n = size_t(side) * side;
  pixels.resize(n);
  postTraversal.resize(n);
  dirX.resize(n), dirY.resize(n), dirZ.resize(n), nearestT.resize(n), nearestNode.resize(n), rayPixel.resize(n);
  worldDirection.resize(n);
  const size_t tiles = size_t((side + kRayTile - 1) / kRayTile) * size_t((side + kRayTile - 1) / kRayTile);
  tileBegin.resize(tiles + 1);
  for (auto* v : {&tileAxisX, &tileAxisY, &tileAxisZ, &tileCos, &tileSin}) v->resize(tiles);
}

MicroCounters& MicroCounters::operator+=(const MicroCounters& o) {
  buffers += o.buffers, buffersRayCast += o.buffersRayCast, nodesVisited += o.nodesVisited;
  nodesSplatted += o.nodesSplatted, leavesListed += o.leavesListed, listFlushes += o.listFlushes;
  rayDiscTests += o.rayDiscTests, rayCastSeconds += o.rayCastSeconds;
  return *this;
}

namespace {

// Bottom up over the decoded nodes: a point of child C (within its sphere and its slab of half-width
// t_C about its plane) lies within |(c_C - c_P) . a_P| + r_C sin(theta) + t_C |cos(theta)| of the
// parent's plane, theta the angle between their axes. Padded for float rounding.
template <class Nodes>
void computeThickness(const Nodes& nodes, uint32_t leafCount, std::vector<float>& thickness) {
  thickness.assign(size_t(2) * leafCount, 0.0f);
  for (uint32_t i = leafCount; i-- > kRootNode;) {
    const TraversalNode parent = nodes(i);
    float t = 0;
    for (const uint32_t c : {firstChild(i), firstChild(i) + 1}) {
      const TraversalNode child = nodes(c);
      const float cosTheta = std::abs(dot(child.axis, parent.axis));
      const float sinTheta = length(cross(child.axis, parent.axis));
      t = std::max(t, std::abs(dot(child.center - parent.center, parent.axis)) + child.radius * sinTheta +
                          thickness[c] * cosTheta);
    }
    thickness[i] = t * 1.0001f + 1e-6f * parent.radius;
  }
}

}  // namespace

MicroHierarchy prepareMicroHierarchy(const PointHierarchy& h) {
  MicroHierarchy m;
  m.hierarchy = &h;
  for (int code = 0; code < 256; ++code) {
    const float angle = float(code) * (kPi / kPackedConeLevels);
    m.coneSin[code] = code == 255 ? 0.0f : std::sin(angle);
    m.coneCos[code] = code == 255 ? -1.0f : std::cos(angle);
  }
  if (h.encoding == NodeEncoding::Float) {
    m.floatNodes.resize(h.floatNodes.size());
    for (size_t i = 1; i < h.floatNodes.size(); ++i) {
      const FloatNode& f = h.floatNodes[i];
      const bool all = f.cone.angle >= kPi;
      m.floatNodes[i] = {f.sphere.center, f.sphere.radius, f.cone.axis, all ? 0.0f : std::sin(f.cone.angle),
                         all ? -1.0f : std::cos(f.cone.angle)};
    }
    computeThickness(FloatNodes{m.floatNodes.data()}, h.leafCount, m.thickness);
  } else {
    computeThickness(PackedNodes{h.packedNodes.data(), h.quantization, m.coneSin, m.coneCos}, h.leafCount, m.thickness);
  }
  return m;
}

void renderMicroBuffer(const MicroHierarchy& mh, const GatherPoint& gather, const HemisphereMapping& mapping,
                       const MicroRenderSettings& settings, MicroBuffer& buffer, MicroCounters& counters) {
  const PointHierarchy& h = *mh.hierarchy;
  if (buffer.side != mapping.width) buffer.resize(mapping.width);
  if (h.encoding == NodeEncoding::Packed) {
    const PackedNodes nodes{h.packedNodes.data(), h.quantization, mh.coneSin, mh.coneCos};
    MicroRasterizer(nodes, h.nodeAreas.data(), mh.thickness.data(), h.leafCount, gather, mapping, settings, buffer,
                    counters)
        .run();
  } else {
    const FloatNodes nodes{mh.floatNodes.data()};
    MicroRasterizer(nodes, h.nodeAreas.data(), mh.thickness.data(), h.leafCount, gather, mapping, settings, buffer,
                    counters)
        .run();
  }
}

Rgb convolveMicroBuffer(const MicroBuffer& b, const HemisphereMapping& m, std::span<const Rgb> radiance) {
  return convolve(b, m, [&](uint32_t node) { return radiance[node]; });
}

Rgb convolveMicroBuffer(const MicroBuffer& b, const HemisphereMapping& m, std::span<const HalfRgb> radiance) {
  return convolve(b, m, [&](uint32_t node) { return toFloat(radiance[node]); });
}

}  // namespace lucent
