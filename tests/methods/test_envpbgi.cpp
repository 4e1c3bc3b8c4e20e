// Point-based GI under environment lighting (--method envpbgi): the primary points form a cut and
// cover what the camera sees; the traversals give the sets of a plain recursion on random
// hierarchies, with any thread count; propagation keeps area-weighted light exactly; a white
// furnace and a closed box give their analytic answers; the paper's approximations against its
// brute force, and the method against the path tracer at one indirect bounce.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <functional>
#include <vector>

#include "lucent/core/parallel.h"
#include "lucent/core/rng.h"
#include "lucent/image/metrics.h"
#include "lucent/methods/envpbgi.h"
#include "lucent/methods/pathtrace.h"
#include "lucent/scene/loader.h"
#include "lucent/techniques/microbuffers/micro_buffer.h"
#include "lucent/techniques/points/node_tree.h"
#include "methods/envpbgi/env_lighting.h"
#include "methods/envpbgi/radiance_cache.h"
#include "methods/envpbgi/visible_points.h"
#include "test_scenes.h"
#include "test_support.h"

using namespace lucent;

namespace {

const std::string kPrimitives = LUCENT_SOURCE_DIR "/scenes/primitives.json";

Scene loadAt(const std::string& path, int width, int height) {
  Scene scene = loadScene(path, LoadOptions(true));
  scene.camera.width = width, scene.camera.height = height;
  scene.contentHash = sceneContentHash(scene);
  return scene;
}

// A hierarchy of n leaves with nothing but its tree and random areas, for the traversals.
EnvHierarchy bareHierarchy(uint32_t n, Rng& rng) {
  EnvHierarchy h;
  h.points.leafCount = n;
  h.nodes.assign(size_t(2) * n, EnvPointNode{});
  h.points.nodeAreas.assign(size_t(2) * n, 0.0f);
  for (uint32_t i = n; i < 2 * n; ++i) h.points.nodeAreas[i] = 0.1f + rng.uniform();
  for (uint32_t i = n; i-- > kRootNode;) h.points.nodeAreas[i] = h.points.nodeAreas[2 * i] + h.points.nodeAreas[2 * i + 1];
  return h;
}

// A random cut (each node on the path down ends it with probability `stop`, leaves always) as the
// primary points, and random secondary points, denser below the cut's nodes.
std::vector<uint32_t> randomSelection(EnvHierarchy& h, Rng& rng, float stop, float secondary) {
  const uint32_t n = h.leafCount();
  std::vector<uint32_t> primary;
  std::function<void(uint32_t)> descend = [&](uint32_t i) {
    if (isLeafNode(i, n) || rng.uniform() < stop) {
      primary.push_back(i);
      return;
    }
    descend(firstChild(i));
    descend(secondChild(i));
  };
  descend(kRootNode);
  std::sort(primary.begin(), primary.end());
  for (uint32_t p : primary) h.nodes[p].selection |= kPrimary;
  for (uint32_t i = kRootNode; i < 2 * n; ++i)
    if (rng.uniform() < secondary) h.nodes[i].selection |= kSecondary;
  return primary;
}

// The selection by plain recursion: covered and derivable bottom-up, under-primary top-down.
std::vector<uint32_t> serialSelection(const EnvHierarchy& h, bool primarySources) {
  const uint32_t n = h.leafCount();
  std::vector<uint32_t> bits(size_t(2) * n, 0);
  const uint32_t source = primarySources ? kSecondary | kPrimary : kSecondary;
  std::function<bool(uint32_t)> covered = [&](uint32_t i) {
    const uint32_t sel = h.nodes[i].selection;
    bits[i] |= sel & (kPrimary | kSecondary);
    bool children = false;
    if (!isLeafNode(i, n)) {
      const bool a = covered(firstChild(i)), b = covered(secondChild(i));
      children = a && b;
    }
    const bool c = (sel & source) != 0 || children;
    if (c) bits[i] |= kCovered;
    if ((sel & kSecondary) && children) bits[i] |= kDerivable;
    return c;
  };
  covered(kRootNode);
  std::function<void(uint32_t, bool)> down = [&](uint32_t i, bool under) {
    if (under && (h.nodes[i].selection & kSecondary)) bits[i] |= kUnderPrimary;
    if (isLeafNode(i, n)) return;
    const bool below = under || (h.nodes[i].selection & kPrimary);
    down(firstChild(i), below);
    down(secondChild(i), below);
  };
  down(kRootNode, false);
  for (uint32_t i = kRootNode; i < 2 * n; ++i)
    if ((bits[i] & kSecondary) && !(bits[i] & (kDerivable | kUnderPrimary | kPrimary))) bits[i] |= kOwnBuffer;
  return bits;
}

}  // namespace

TEST_CASE("envpbgi: the paper's node is 48 bytes and its links are the tree's", "[envpbgi]") {
  const Scene scene = loadAt(kPrimitives, 64, 36);
  PointHierarchyOptions ho;
  ho.pointCount = 1u << 10;
  ho.encoding = NodeEncoding::Float;
  ho.sampling.method = PointSampling::LowDiscrepancy;
  const EnvHierarchy h = makeEnvHierarchy(buildPointHierarchy(scene, ho));
  const uint32_t n = h.leafCount();
  for (uint32_t i = kRootNode; i < 2 * n; ++i) {
    const EnvPointNode& node = h.nodes[i];
    REQUIRE(node.skip == nextNodeSkippingSubtree(i));
    if (isLeafNode(i, n)) {
      REQUIRE(node.child[0] == 0);
    } else {
      REQUIRE(node.child[0] == firstChild(i));
      REQUIRE(node.child[1] == secondChild(i));
      // The surfel is its leaves' area-weighted mean.
      double sum[3] = {0, 0, 0}, area = 0;
      for (uint32_t j = 0; j < leavesBelow(i, n); ++j) {
        const uint32_t leaf = n + firstLeafPoint(i, n) + j;
        for (int c = 0; c < 3; ++c) sum[c] += double(h.surfels[leaf].position[c]) * h.points.nodeAreas[leaf];
        area += h.points.nodeAreas[leaf];
      }
      for (int c = 0; c < 3; ++c) REQUIRE(h.surfels[i].position[c] == Approx(sum[c] / area).margin(1e-4));
    }
    REQUIRE(node.radius == h.points.floatNodes[i].sphere.radius);
  }
}

TEST_CASE("envpbgi: the primary points are a cut and cover what the camera sees", "[envpbgi]") {
  const Scene scene = loadAt(kPrimitives, 160, 90);
  const Visibility vis(scene);
  PointHierarchyOptions ho;
  ho.pointCount = 1u << 14;
  ho.encoding = NodeEncoding::Float;
  ho.sampling.method = PointSampling::LowDiscrepancy;
  EnvHierarchy h = makeEnvHierarchy(buildPointHierarchy(scene, ho));
  const MicroHierarchy micro = prepareMicroHierarchy(h.points);
  const uint32_t n = h.leafCount();
  const CameraDepth depth = traceCameraDepth(scene, vis);
  const float pixelAngle = PinholeCamera(scene.camera).pixelAngle();
  for (const float pixels : {20.0f, 640.0f}) {
    for (EnvPointNode& node : h.nodes) node.selection = 0;
    PrimarySelection selection;
    selection.maxSolidAngle = pixels * pixelAngle * pixelAngle;
    selection.maxConeAngle = kPi / 6;
    selection.thickness = micro.thickness;
    const std::vector<uint32_t> primary = selectPrimaryPoints(h, scene.camera, depth, selection);
    INFO(pixels << " pixels: " << primary.size() << " primary points");
    REQUIRE(primary.size() > 20);
    // A cut: no primary point above another.
    for (uint32_t leaf = n; leaf < 2 * n; ++leaf) {
      int above = 0;
      for (uint32_t i = leaf; i != kTraversalEnd; i = parentNode(i)) above += (h.nodes[i].selection & kPrimary) != 0;
      REQUIRE(above <= 1);
    }
    // Covering: the leaf nearest to what a pixel sees lies below a primary point, for all but a few
    // pixels (a node's image is sampled by at most 8 x 8 pixels).
    const PinholeCamera camera(scene.camera);
    int seen = 0, covered = 0;
    for (int y = 0; y < depth.height; y += 3)
      for (int x = 0; x < depth.width; x += 3) {
        const float t = depth.depth[size_t(y) * depth.width + x];
        if (!(t < kInf)) continue;
        const Ray ray = camera.generate(float(x) + 0.5f, float(y) + 0.5f);
        const Vec3 hit = ray.origin + ray.direction * t;
        uint32_t nearest = n;
        float best = kInf;
        for (uint32_t leaf = n; leaf < 2 * n; ++leaf) {
          const float d = length(h.surfels[leaf].position - hit);
          if (d < best) best = d, nearest = leaf;
        }
        ++seen;
        bool below = false;
        for (uint32_t i = nearest; i != kTraversalEnd; i = parentNode(i)) below |= (h.nodes[i].selection & kPrimary) != 0;
        covered += below;
      }
    INFO(covered << " of " << seen << " pixels see a leaf below a primary point");
    REQUIRE(seen > 1000);
    CHECK(covered >= 0.995 * seen);
  }
}

TEST_CASE("envpbgi: the upward and downward traversals give the plain recursion's sets", "[envpbgi]") {
  Rng rng(13);
  for (const uint32_t n : {2u, 64u, 4096u})
    for (const bool primarySources : {false, true})
      for (const int threads : {1, 2}) {
        ParallelScope scope(threads);
        EnvHierarchy h = bareHierarchy(n, rng);
        const std::vector<uint32_t> primary = randomSelection(h, rng, 0.15f, 0.3f);
        const std::vector<uint32_t> expected = serialSelection(h, primarySources);
        const SelectionCounts counts = selectDirectLightPoints(h, primary, primarySources);
        INFO(n << " leaves, primary sources " << primarySources << ", threads " << threads);
        uint64_t own = 0;
        for (uint32_t i = kRootNode; i < 2 * n; ++i) {
          REQUIRE(h.nodes[i].selection == expected[i]);
          own += (expected[i] & kOwnBuffer) != 0;
        }
        REQUIRE(counts.ownBuffers == own);
        REQUIRE(counts.primary == primary.size());
        REQUIRE(counts.secondary >= counts.afterUpward);
        REQUIRE(counts.afterUpward >= counts.afterDownward);
        REQUIRE(counts.afterDownward >= counts.ownBuffers);
        // Propagation: every secondary point gets light; a derived node holds its children's
        // area-weighted mean, a copied one its primary point's.
        std::vector<Rgb> direct(size_t(2) * n);
        for (uint32_t i = kRootNode; i < 2 * n; ++i)
          if (h.nodes[i].selection & (kPrimary | kOwnBuffer)) direct[i] = Rgb(rng.uniform(), rng.uniform(), rng.uniform());
        const std::vector<Rgb> given = direct;
        propagateDirectLight(h, primary, direct);
        for (uint32_t i = kRootNode; i < 2 * n; ++i) {
          const uint32_t s = h.nodes[i].selection;
          if (s & kSecondary) REQUIRE((s & kHasDirect));
          if ((s & kCovered) && !isLeafNode(i, n) && !(s & kPrimary) && ((s & kDerivable) || !(s & kSecondary))) {
            const float a = h.points.nodeAreas[2 * i], b = h.points.nodeAreas[2 * i + 1];
            for (int c = 0; c < 3; ++c)
              REQUIRE(direct[i][c] * (a + b) == Approx(direct[2 * i][c] * a + direct[2 * i + 1][c] * b).epsilon(1e-5));
          } else if ((s & kSecondary) && !(s & kPrimary) && !(s & kOwnBuffer)) {
            // Copied from its primary ancestor.
            uint32_t p = parentNode(i);
            while (!(h.nodes[p].selection & kPrimary)) p = parentNode(p);
            REQUIRE(direct[i] == direct[p]);
          } else if (s & (kPrimary | kOwnBuffer)) {
            REQUIRE(direct[i] == given[i]);
          }
        }
      }
}

TEST_CASE("envpbgi: buffers rendered together in packets of their own order are each one's alone", "[envpbgi]") {
  // renderBuffers packs its origins by facing and Morton code, not in the order given: every buffer
  // must still be the one its origin gets rendered alone, in its own slot.
  const Scene scene = loadAt(kPrimitives, 64, 36);
  PointHierarchyOptions ho;
  ho.pointCount = 1u << 12;
  ho.encoding = NodeEncoding::Float;
  const EnvHierarchy h = makeEnvHierarchy(buildPointHierarchy(scene, ho));
  const MicroHierarchy micro = prepareMicroHierarchy(h.points);
  MicroRenderSettings settings;
  settings.depth = DepthCoding::forExtent(length(scene.bounds.extent()));
  settings.splatReach = 2;
  const BufferQuadrature q = makeQuadrature(MappingKind::Paraboloid, 8);
  // Nodes of every level, in an order unlike the packing's.
  std::vector<uint32_t> nodes;
  for (uint32_t i = kRootNode + 3; i < uint32_t(h.nodes.size()); i += 97) nodes.push_back(i);
  std::reverse(nodes.begin(), nodes.end());
  auto origin = [&](size_t k) { return surfelOrigin(h.surfels[nodes[k]]); };
  MicroCounters counters;
  std::vector<uint32_t> together(nodes.size() * q.texels()), alone(q.texels());
  renderBuffers(micro, settings, q, nodes.size(), origin, together, counters);
  for (size_t k = 0; k < nodes.size(); ++k) {
    renderBuffers(micro, settings, q, 1, [&](size_t) { return origin(k); }, alone, counters);
    CAPTURE(k, nodes[k]);
    REQUIRE(std::equal(alone.begin(), alone.end(), together.begin() + ptrdiff_t(k * q.texels())));
  }
}

TEST_CASE("envpbgi: a buffer's quadrature integrates a constant radiance exactly", "[envpbgi]") {
  for (const MappingKind kind : {MappingKind::Paraboloid, MappingKind::Nusselt})
    for (const int side : {8, 16, 24}) {
      const BufferQuadrature q = makeQuadrature(kind, side);
      double sum = 0;
      for (float w : q.cosineWeight) sum += w;
      REQUIRE(sum == Approx(kPi).epsilon(1e-6));
      // The pre-convolution's zenith texel is the same sum.
      const CacheConvolution c = makeCacheConvolution(q);
      double zenith = 0;
      for (uint32_t t = 0; t < q.texels(); ++t) zenith += c.weights[size_t(kCacheTexels / 2) * q.texels() + t];
      REQUIRE(zenith == Approx(kPi).epsilon(1e-5));
    }
}

TEST_CASE("envpbgi: tile lists cut to the receivers' depths interpolate as the whole lists", "[envpbgi]") {
  // Caches in front of a camera, or around one inside their cloud (spheres through the eye's plane,
  // receivers behind it); receivers near the caches (most within one's radius), some nowhere near
  // one (fallbacks), one at NaN. Every receiver's interpolation from its tile's cut list must be
  // the one from the tile's whole list and Eq. 5 summed one cache at a time with cacheIrradiance,
  // bit for bit, with the receivers cut in one band and in two.
  Rng rng(7, 1);
  std::vector<RadianceCache> caches(400);
  for (RadianceCache& c : caches) {
    c.position = {6 * rng.uniform() - 3, 6 * rng.uniform() - 3, -2 - 10 * rng.uniform()};
    c.normal = normalize(Vec3{0, 0, 1} + sampleUniformSphere(rng.uniform2()) * 0.8f);
    c.radius = 0.2f + 0.8f * rng.uniform();
    for (int t = 0; t < kCacheTexels; ++t) c.environment[t] = Rgb(rng.uniform()), c.indirect[t] = Rgb(rng.uniform());
  }
  Interpolation interpolation;
  interpolation.maxAngle = 20 * kPi / 180;
  const float cosMax = std::cos(interpolation.maxAngle);
  for (const Vec3 eye : {Vec3{0, 0, 0}, Vec3{0, 0, -6}}) {
    Camera camera;
    camera.eye = eye, camera.lookAt = eye + Vec3{0, 0, -1};
    camera.fovY = 60, camera.width = 256, camera.height = 192;
    const CacheGrid grid = buildCacheGrid(caches, camera, 8);
    const PinholeCamera pinhole(camera);
    struct Receiver {
      Vec3 x, n;
      uint32_t tile = 0;
      float depth = 0;
    };
    std::vector<Receiver> receivers(3000);
    for (Receiver& r : receivers) {
      const RadianceCache& c = caches[size_t(rng.uniform() * float(caches.size()))];
      const bool near = rng.uniform() < 0.9f;
      r.x = near ? c.position + sampleUniformSphere(rng.uniform2()) * (c.radius * rng.uniform())
                 : Vec3{6 * rng.uniform() - 3, 6 * rng.uniform() - 3, -2 - 30 * rng.uniform()};
      r.n = normalize(c.normal + sampleUniformSphere(rng.uniform2()) * 0.3f);
    }
    receivers[1234].x = Vec3{std::nanf(""), 0, -5};
    for (Receiver& r : receivers) {
      const uint32_t pixel = uint32_t(rng.uniform() * float(camera.width * camera.height));
      const CacheGrid::Placement at = grid.place(pinhole, r.x, pixel, camera.width, camera.height);
      r.tile = at.tile, r.depth = at.depth;
    }
    // Eq. 5 over the tile's whole list, one cache at a time.
    auto reference = [&](const Receiver& r, bool& fallback) {
      BufferIrradiance sum;
      double total = 0;
      for (uint32_t j = grid.begin[r.tile]; j < grid.begin[r.tile + 1]; ++j) {
        const RadianceCache& c = caches[grid.caches[j]];
        const float distance = length(r.x - c.position), cosine = dot(r.n, c.normal);
        if (!(distance < c.radius && cosine >= cosMax)) continue;
        const float w = 1.0f / std::max(distance / c.radius + std::sqrt(std::max(0.0f, 1.0f - cosine)), 1e-6f);
        const BufferIrradiance e = cacheIrradiance(c, r.n);
        sum.environment += e.environment * w, sum.nodes += e.nodes * w;
        total += w;
      }
      fallback = !(total > 0);
      return fallback ? BufferIrradiance{} : BufferIrradiance{sum.environment * float(1.0 / total), sum.nodes * float(1.0 / total)};
    };
    auto same = [](const BufferIrradiance& a, const BufferIrradiance& b) {
      for (int ch = 0; ch < 3; ++ch)
        if (!(a.environment[ch] == b.environment[ch] && a.nodes[ch] == b.nodes[ch])) return false;
      return true;
    };
    size_t behind = 0;
    for (const Receiver& r : receivers) behind += r.depth < 0;
    if (eye.z < 0) CHECK(behind > 100);
    for (const size_t bands : {1, 2}) {
      size_t whole = 0, cut = 0, qualified = 0;
      for (size_t band = 0; band < bands; ++band) {
        const size_t first = band * receivers.size() / bands, last = (band + 1) * receivers.size() / bands;
        std::vector<uint32_t> tileOf;
        std::vector<float> depthOf;
        for (size_t i = first; i < last; ++i) tileOf.push_back(receivers[i].tile), depthOf.push_back(receivers[i].depth);
        TileLists lists;
        cutTileLists(grid, tileOf, depthOf, lists);
        for (size_t i = first; i < last; ++i) {
          const Receiver& r = receivers[i];
          const std::span<const uint32_t> all(grid.caches.data() + grid.begin[r.tile],
                                              grid.begin[r.tile + 1] - grid.begin[r.tile]);
          bool fallbackReference = false;
          const std::optional<BufferIrradiance> a = interpolateCaches(caches, grid, all, r.x, r.n, interpolation);
          const std::optional<BufferIrradiance> b =
              interpolateCaches(caches, grid, lists.of(grid, r.tile), r.x, r.n, interpolation);
          const BufferIrradiance expected = reference(r, fallbackReference);
          CAPTURE(eye.z, bands, i);
          REQUIRE(a.has_value() == !fallbackReference);
          REQUIRE(b.has_value() == !fallbackReference);
          if (a) {
            REQUIRE(same(*a, *b));
            REQUIRE(same(*a, expected));
          }
          whole += all.size(), cut += lists.of(grid, r.tile).size(), qualified += a.has_value();
        }
      }
      // The cut matters, and most receivers have caches to average.
      CHECK(cut < whole * 9 / 10);
      CHECK(qualified > receivers.size() / 3);
    }
  }
}

TEST_CASE("envpbgi: a plane under a uniform environment is its albedo times the radiance (white furnace)", "[envpbgi]") {
  Scene scene;
  Material ground;
  ground.kd = Rgb(0.6f, 0.4f, 0.2f);
  test::addQuad(scene, {-50, 0, -50}, {-50, 0, 50}, {50, 0, 50}, {50, 0, -50}, test::addMaterial(scene, ground, "ground"));
  scene.environment.present = true;
  scene.environment.radiance = Rgb(1.5f);
  scene.camera = test::testCamera({0, 3, 0}, {0.2f, 0, -1}, 48, 32, 70);
  finalizeScene(scene);
  const Visibility vis(scene);
  EnvPbgiOptions o;
  o.points = 1u << 12;
  o.common.layers = true;
  for (const PointDirectLight directLight : {PointDirectLight::Selected, PointDirectLight::EveryLeaf}) {
    o.directLight = directLight;
    const RenderOutput out = renderEnvPbgi(scene, vis, o);
    const Image& image = out.image;
    INFO("direct light " << int(directLight));
    for (int y = 0; y < image.height(); ++y)
      for (int x = 0; x < image.width(); ++x) {
        if (image.at(x, y, image.channelIndex("depth.Z")) == 0) continue;  // the sky
        for (int c = 0; c < 3; ++c) REQUIRE(image.at(x, y, c) == Approx(1.5f * ground.kd[c]).epsilon(1e-4));
        REQUIRE(image.at(x, y, image.channelIndex("indirect.R")) == 0.0f);
      }
  }
}

TEST_CASE("envpbgi: the same image with 1 and 2 threads, and a crop of it", "[envpbgi]") {
  const Scene scene = loadAt(kPrimitives, 96, 54);
  const Visibility vis(scene);
  EnvPbgiOptions o;
  o.points = 1u << 14;
  Image images[2];
  for (const int threads : {1, 2}) {
    ParallelScope scope(threads);
    images[threads - 1] = renderEnvPbgi(scene, vis, o).image;
  }
  REQUIRE(images[0].pixels() == images[1].pixels());
  RenderControl crop;
  crop.crop = {10, 7, 50, 40};
  const Image part = renderEnvPbgi(scene, vis, o, crop).image;
  for (int y = 7; y < 40; ++y)
    for (int x = 10; x < 50; ++x)
      for (int c = 0; c < 3; ++c) REQUIRE(part.at(x - 10, y - 7, c) == images[0].at(x, y, c));
}

TEST_CASE("envpbgi: pixels shaded band by band give the image of one band", "[envpbgi]") {
  // 480 x 300 is more camera samples than a band holds; with a dump, the pixels are one band.
  const Scene scene = loadAt(kPrimitives, 480, 300);
  const Visibility vis(scene);
  EnvPbgiOptions o;
  o.points = 1u << 14;
  const Image bands = renderEnvPbgi(scene, vis, o).image;
  const test::TempDir dir("envpbgi-bands");
  o.dumpDirectory = dir.path.string();
  const Image whole = renderEnvPbgi(scene, vis, o).image;
  REQUIRE(bands.pixels() == whole.pixels());
}

TEST_CASE("envpbgi: the paper's approximations against its brute force, and both against the path tracer", "[envpbgi]") {
  // Fig. 8: direct light by a micro-buffer at every leaf and a micro-buffer at every pixel. The
  // paper calls the difference negligible; the issue's reading of that: relMSE at most 0.01. The
  // path tracer at one indirect bounce (max depth 2) through the pixels' centres is the transport
  // both approximate.
  const Scene scene = loadAt(kPrimitives, 160, 90);
  const Visibility vis(scene);
  EnvPbgiOptions o;
  o.points = 1u << 16;
  const RenderOutput paper = renderEnvPbgi(scene, vis, o);
  o.directLight = PointDirectLight::EveryLeaf;
  o.pixelIrradiance = PixelIrradiance::EveryPixel;
  const RenderOutput bruteForce = renderEnvPbgi(scene, vis, o);
  PathTraceOptions pt;
  pt.maxDepth = 2;
  pt.common.spp = 512;
  pt.pixelCentres = true;
  const RenderOutput reference = renderPathTraced(scene, vis, pt);
  auto relMse = [](const Image& a, const Image& b) { return compareImages(a, b).overall.relmse; };
  const double approximations = relMse(paper.image, bruteForce.image);
  const double paperError = relMse(paper.image, reference.image), bruteError = relMse(bruteForce.image, reference.image);
  INFO("relMSE: paper against brute force " << approximations << ", against the path tracer " << paperError
                                            << ", brute force against the path tracer " << bruteError);
  CHECK(approximations <= 0.01);
  CHECK(paperError <= 0.02);
  CHECK(bruteError <= 0.02);
  // Far fewer micro-buffers than the brute force's (every leaf and every pixel).
  uint64_t paperBuffers = 0, bruteBuffers = 0;
  for (const auto& [name, value] : paper.stats.counters)
    if (name == "micro_buffers") paperBuffers = value;
  for (const auto& [name, value] : bruteForce.stats.counters)
    if (name == "micro_buffers") bruteBuffers = value;
  CHECK(paperBuffers * 10 < bruteBuffers);
}

TEST_CASE("envpbgi: glossy receivers are shaded by their diffuse part, counted, and lose light gracefully", "[envpbgi]") {
  // The paper's receivers are diffuse. On the primitives scene with a glossy ground and glossy
  // white objects (scenes/primitives-glossy.json), every glossy shading point is counted, the image
  // stays finite, and the error against the path tracer (max depth 2) grows from the diffuse
  // scene's by the lobes' light, which is lost, never added: each channel's mean is below the path
  // tracer's. Measured at this size: relMSE 0.027 against the diffuse scene's 0.0047.
  auto errorOf = [](const std::string& path, RenderOutput& out, RenderOutput& reference) {
    const Scene scene = loadAt(path, 160, 90);
    const Visibility vis(scene);
    EnvPbgiOptions o;
    o.points = 1u << 16;
    out = renderEnvPbgi(scene, vis, o);
    PathTraceOptions pt;
    pt.maxDepth = 2;
    pt.common.spp = 512;
    pt.pixelCentres = true;
    reference = renderPathTraced(scene, vis, pt);
    return compareImages(out.image, reference.image).overall.relmse;
  };
  RenderOutput diffuse, diffuseReference, glossy, glossyReference;
  const double diffuseError = errorOf(kPrimitives, diffuse, diffuseReference);
  const double glossyError = errorOf(LUCENT_SOURCE_DIR "/scenes/primitives-glossy.json", glossy, glossyReference);
  INFO("relMSE against the path tracer: diffuse " << diffuseError << ", glossy " << glossyError);
  CHECK(diffuse.stats.counter("glossy_shaded_diffuse") == 0);
  CHECK(glossy.stats.counter("glossy_shaded_diffuse") > glossy.stats.counter("shading_points") / 2);
  CHECK(glossy.stats.counter("invalid_samples") == 0);
  for (const float v : glossy.image.pixels()) REQUIRE(std::isfinite(v));
  CHECK(glossyError > 2 * diffuseError);
  CHECK(glossyError < 0.1);
  for (int c = 0; c < 3; ++c) CHECK(test::channelMean(glossy.image, c).mean < test::channelMean(glossyReference.image, c).mean);
}

TEST_CASE("envpbgi refuses emitting triangles and a brute-force gather without light at every node", "[envpbgi]") {
  Scene scene = test::furnaceBox(Rgb(0.5f), Rgb(1.0f), test::testCamera({0, 0, 0}, {0, 0, -1}, 8, 8));
  const Visibility vis(scene);
  EnvPbgiOptions o;
  o.points = 1u << 10;
  REQUIRE_THROWS_WITH(renderEnvPbgi(scene, vis, o), Catch::Contains("emitting triangles"));
  o.pixelIrradiance = PixelIrradiance::EveryPixel;
  REQUIRE_THROWS_WITH(envPbgiOptionTable().validate(o), Catch::Contains("every-leaf"));
}
