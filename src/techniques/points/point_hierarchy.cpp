// Building the point hierarchy and computing (and recomputing) its node data (paper 2.1, 3.1).
#include "lucent/techniques/points/point_hierarchy.h"

#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <stdexcept>
#include <string>

#include "lucent/core/stop.h"
#include "lucent/scene/surface.h"
#include "lucent/techniques/points/bottom_up.h"

namespace lucent {

namespace {

struct TriangleShape {
  Vec3 normal;
  float area = 0;
};

// The triangle's face normal and area for the current vertex positions, as finalizeScene computes
// them (triangleGeometry), so that undeformed leaves match scene.faceNormals and faceAreas bit for bit.
TriangleShape triangleShape(const Scene& scene, uint32_t tri) {
  const TriangleGeometry g = triangleGeometry(scene.vertex(tri, 0), scene.vertex(tri, 1), scene.vertex(tri, 2));
  // A triangle deformed to nothing keeps the scene's normal and stands for no area.
  if (!(g.area > 0)) return {scene.faceNormals[tri], 0.0f};
  return {g.normal, g.area};
}

// Diffuse albedo at the point (its lobe's Lambertian term), its textures looked up at its uv (a glTF
// material's diffuse colour, (1 - metallic) times the base colour); specular lobes (mirror, glass)
// have none and get 0.
Rgb pointAlbedo(const Scene& scene, const PointSample& s) {
  const Material& m = scene.materials[scene.materialIds[s.triangle]];
  if (!lobeVariesOverSurface(scene, m)) return materialBsdf(m).diffuse();
  SurfacePoint sp;
  sp.triangle = s.triangle;
  sp.materialId = scene.materialIds[s.triangle];
  sp.b1 = s.b1;
  sp.b2 = s.b2;
  return bsdfAt(scene, sp).diffuse();
}

void computeLeaves(PointHierarchy& h, const Scene& scene) {
  const uint32_t n = h.leafCount;
  const float restArea = h.restPointArea, scale = h.discAreaScale;
  points::parallelFor(0, n, [&](uint32_t j) {
    const PointSample& s = h.points[j];
    const TriangleShape shape = triangleShape(scene, s.triangle);
    // The point stands for restPointArea of its triangle at rest; the triangle's stretch scales it.
    const float area = restArea * (shape.area / h.restTriangleAreas[s.triangle]);
    h.nodeAreas[n + j] = area;
    h.floatNodes[n + j] = {{pointPosition(scene, s), std::sqrt(scale * area / kPi)},
                           {shape.normal, 0.0f},
                           pointAlbedo(scene, s)};
  });
}

void computeInterior(PointHierarchy& h) {
  points::forEachInteriorBottomUp(h.leafCount, [&](uint32_t i) {
    const FloatNode& a = h.floatNodes[firstChild(i)];
    const FloatNode& b = h.floatNodes[secondChild(i)];
    const float areaA = h.nodeAreas[firstChild(i)], areaB = h.nodeAreas[secondChild(i)];
    const float area = areaA + areaB;
    h.nodeAreas[i] = area;
    const Rgb albedo = area > 0 ? (a.albedo * areaA + b.albedo * areaB) / area : (a.albedo + b.albedo) * 0.5f;
    h.floatNodes[i] = {mergeSpheres(a.sphere, b.sphere), mergeCones(a.cone, b.cone), albedo};
  });
}

// The packed frame: the leaves' centres' box in 65535 steps per axis (interior centres lie in the
// leaves' convex hull), radii up to the largest float radius plus 1% (packed spheres grow over
// float ones only by a few steps per level).
NodeQuantization quantizationFor(const PointHierarchy& h) {
  const uint32_t n = h.leafCount;
  struct Extent {
    Bounds3 box;
    float maxRadius = 0;
  };
  // Min and max are exact: the reduction's order does not matter.
  const Extent e = tbb::parallel_reduce(
      tbb::blocked_range<uint32_t>(1, 2 * n, points::kNodeGrain), Extent{},
      [&](const tbb::blocked_range<uint32_t>& r, Extent acc) {
        for (uint32_t i = r.begin(); i != r.end(); ++i) {
          if (i >= n) acc.box.extend(h.floatNodes[i].sphere.center);
          acc.maxRadius = std::max(acc.maxRadius, h.floatNodes[i].sphere.radius);
        }
        return acc;
      },
      [](Extent a, const Extent& b) {
        if (!b.box.empty()) a.box.extend(b.box.lo), a.box.extend(b.box.hi);
        a.maxRadius = std::max(a.maxRadius, b.maxRadius);
        return a;
      });
  NodeQuantization q;
  q.origin = e.box.lo;
  const Vec3 ext = e.box.extent();
  const float largest = std::max({ext.x, ext.y, ext.z, e.maxRadius});
  // A flat axis still needs a positive step; a tiny one keeps its coordinates exact.
  const float floor = std::max(largest * 1e-6f, 1e-30f);
  for (int a = 0; a < 3; ++a) q.step[a] = std::max(ext[a], floor) / 65535.0f;
  q.radiusStep = std::max(e.maxRadius * 1.01f, floor) / 65535.0f;
  return q;
}

// Packed nodes: leaves from their float values; interior spheres merged from the children's decoded
// spheres, so each packed sphere contains its packed children; cones and albedo from the float node,
// so packed cones do not widen level after level.
void computePacked(PointHierarchy& h) {
  const uint32_t n = h.leafCount;
  h.quantization = quantizationFor(h);
  const NodeQuantization& q = h.quantization;
  h.packedNodes.resize(h.nodeCount());
  // Leaves of one triangle have the same cone, so the same normal and cone bits: neighbours in tree
  // order mostly share a triangle and reuse them (identical input, identical bits).
  tbb::parallel_for(tbb::blocked_range<uint32_t>(n, 2 * n, points::kNodeGrain), [&](const auto& r) {
    stopPoint();
    NormalCone lastCone{Vec3(kInf), kInf};
    PackedNode lastBits;
    for (uint32_t i = r.begin(); i != r.end(); ++i) {
      const FloatNode& f = h.floatNodes[i];
      PackedNode p;
      encodeSphere(f.sphere, q, p);
      if (f.cone.axis == lastCone.axis && f.cone.angle == lastCone.angle) {
        p.normalAlbedo = lastBits.normalAlbedo & 0x7fffu;
        p.coneFree = lastBits.coneFree;
      } else {
        encodeCone(f.cone, p);
        lastCone = f.cone, lastBits = p;
      }
      encodeAlbedo(f.albedo, p);
      h.packedNodes[i] = p;
    }
  });
  points::forEachInteriorBottomUp(n, [&](uint32_t i) {
    const Sphere s = mergeSpheres(decodeSphere(h.packedNodes[firstChild(i)], q),
                                  decodeSphere(h.packedNodes[secondChild(i)], q));
    h.packedNodes[i] = encodeNode(s, h.floatNodes[i].cone, h.floatNodes[i].albedo, q);
  });
}

void checkOptions(const PointHierarchyOptions& o, size_t pointCount) {
  if (pointCount == 0 || !std::has_single_bit(pointCount) || pointCount > (size_t(1) << 26))
    throw std::invalid_argument("point hierarchy: the point count must be a power of two from 1 to 2^26, not " +
                                std::to_string(pointCount));
  if (!(o.discAreaScale > 0) || !std::isfinite(o.discAreaScale))
    throw std::invalid_argument("point hierarchy: discAreaScale must be positive");
  if (o.encoding != NodeEncoding::Float && o.encoding != NodeEncoding::Packed)
    throw std::invalid_argument("point hierarchy: unknown node encoding");
}

}  // namespace

PointHierarchy buildPointHierarchy(const Scene& scene, const PointHierarchyOptions& options, RenderStats* stats) {
  checkOptions(options, options.pointCount);
  return buildPointHierarchy(scene, samplePoints(scene, options.pointCount, options.sampling, stats), options, stats);
}

PointHierarchy buildPointHierarchy(const Scene& scene, std::vector<PointSample> points,
                                   const PointHierarchyOptions& options, RenderStats* stats) {
  checkOptions(options, points.size());
  for (const PointSample& s : points)
    if (s.triangle >= scene.triangleCount())
      throw std::invalid_argument("point hierarchy: a point's triangle is not in the scene");
  PointHierarchy h;
  h.leafCount = uint32_t(points.size());
  h.encoding = options.encoding;
  h.discAreaScale = options.discAreaScale;

  beginStage("median_split");
  Stopwatch splitClock;
  std::vector<Vec3> positions(points.size());
  points::parallelFor(0, h.leafCount, [&](uint32_t j) { positions[j] = pointPosition(scene, points[j]); });
  const std::vector<uint32_t> order = medianSplitOrder(positions);
  h.points.resize(points.size());
  points::parallelFor(0, h.leafCount, [&](uint32_t j) { h.points[j] = points[order[j]]; });
  if (stats) {
    stats->addStage("median_split", splitClock.seconds());
    // Emitters keep their points (their emission is the lighting stages' business): say how many.
    uint64_t onEmitters = 0;
    if (scene.triangleLight.size() == scene.triangleCount())
      for (const PointSample& s : h.points) onEmitters += scene.triangleLight[s.triangle] >= 0;
    stats->addCounter("points_on_emitters", onEmitters);
  }

  // The rest state: each point stands for an equal share of the area it was sampled from.
  h.restTriangleAreas.resize(scene.triangleCount());
  double total = 0;
  for (uint32_t t = 0; t < scene.triangleCount(); ++t) total += h.restTriangleAreas[t] = triangleShape(scene, t).area;
  h.restPointArea = float(total / h.leafCount);
  for (const PointSample& s : h.points)
    if (!(h.restTriangleAreas[s.triangle] > 0))
      throw std::invalid_argument("point hierarchy: a point lies on a triangle without area");

  refitPointHierarchy(h, scene, stats);
  return h;
}

void refitPointHierarchy(PointHierarchy& h, const Scene& scene, RenderStats* stats) {
  if (h.restTriangleAreas.size() != scene.triangleCount())
    throw std::invalid_argument("point hierarchy refit: the scene's triangles are not the hierarchy's");
  beginStage("leaf_nodes");
  Stopwatch leafClock;
  h.floatNodes.resize(h.nodeCount());
  h.nodeAreas.resize(h.nodeCount());
  computeLeaves(h, scene);
  if (stats) stats->addStage("leaf_nodes", leafClock.seconds());
  beginStage("interior_nodes");
  Stopwatch interiorClock;
  computeInterior(h);
  if (stats) stats->addStage("interior_nodes", interiorClock.seconds());
  if (h.encoding == NodeEncoding::Packed) {
    beginStage("packed_nodes");
    Stopwatch packClock;
    computePacked(h);
    if (stats) stats->addStage("packed_nodes", packClock.seconds());
  } else {
    h.packedNodes.clear();
  }
}

}  // namespace lucent
