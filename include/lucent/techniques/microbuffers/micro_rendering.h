// Micro-rendering of gather points, a packet of them at once (Ritschel et al. 2009, 2.2, 3.1, 3.2): the point hierarchy's
// cut, found by a stackless depth-first traversal with the solid-angle criterion, rasterized into a
// micro-buffer with a depth test; leaves larger than a pixel resolved by on-demand ray casting; the
// buffer convolved with the BRDF through the mapping's pixel weights.
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "lucent/core/math.h"
#include "lucent/core/stats.h"
#include "lucent/techniques/microbuffers/hemisphere_mapping.h"
#include "lucent/techniques/microbuffers/micro_buffer.h"
#include "lucent/techniques/points/point_hierarchy.h"
#include "lucent/techniques/points/point_radiance.h"

namespace lucent {

// Where gathering happens: a surface point, its frame (shading normal on +z, jittered about it),
// the distance below which hits count as the point's own surface, and the surface's geometric
// normal on the frame's side. Pixels whose direction lies below the geometric surface see the
// surface itself: where a shading normal tilts the frame, they are the wedge that the path tracer's
// leak test ends paths in (leaksThroughSurface), and they hold kBackFaceMicroNode at depth 0, so
// they receive nothing. A zero surfaceNormal cuts nothing (a point in free space).
struct GatherPoint {
  Vec3 position;
  Frame frame;
  float selfDistance = 0;
  Vec3 surfaceNormal;
};

// One lane's micro-buffer, reused from one gather point to the next.
struct MicroBuffer {
  int side = 0;
  std::vector<uint32_t> pixels;         // side x side packed depth | node (micro_buffer.h)
  std::vector<uint32_t> postTraversal;  // leaves to ray-cast, at most side x side (3.1)
  uint32_t listed = 0;
  // Ray-casting scratch, one entry per used pixel of the mapping, in tiles of 4 x 4 pixels.
  std::vector<float> dirX, dirY, dirZ, nearestT;
  std::vector<uint32_t> nearestNode;
  std::vector<uint16_t> rayGridIndex;  // each ray's pixel in `grid` (below)
  // Per pixel, its sample direction in world space (the splats' cone and exact tests, the rays), as
  // three arrays with a border of kMaxSplatReach empty pixels (rows of side + 2 kMaxSplatReach, and a
  // few floats more), so that a splat reads the rows of its window four floats at a time without
  // bounds checks; and the same for the pixels themselves while the buffer is rendered (copied to
  // `pixels` when it is done; the border holds 0, nearer than any node).
  std::vector<float> worldX, worldY, worldZ;
  std::vector<uint32_t> grid;
  // Per tile: its rays [tileBegin[i], tileBegin[i + 1]) and the cone bounding their directions.
  std::vector<uint32_t> tileBegin;
  std::vector<float> tileAxisX, tileAxisY, tileAxisZ, tileCos, tileSin;
  void resize(int bufferSide);
};

struct MicroCounters {
  uint64_t buffers = 0;
  uint64_t buffersRayCast = 0;      // buffers whose post-traversal list was not empty
  uint64_t nodesVisited = 0;        // by each lane: its cut and the nodes it skipped
  uint64_t packetNodesVisited = 0;  // by packets: nodes tested for all their lanes at once
  uint64_t nodesSplatted = 0;       // nodes rasterized into one pixel
  uint64_t backNodesSplatted = 0;   // of them, nodes seen from behind (occluders)
  uint64_t leavesListed = 0;        // leaves put on post-traversal lists
  uint64_t listFlushes = 0;         // lists ray-cast early because they were full
  uint64_t rayDiscTests = 0;
  double rayCastSeconds = 0;        // time spent ray casting, within renderMicroBuffers
  MicroCounters& operator+=(const MicroCounters& o);
  // The counters micro_buffers, micro_buffers_ray_cast, nodes_visited, packet_nodes_visited,
  // nodes_splatted, back_nodes_splatted, leaves_ray_cast, post_traversal_flushes and ray_disc_tests.
  void report(RenderStats& stats) const;
};

struct MicroRenderSettings {
  bool rayCasting = true;  // false: leaves larger than a pixel are splatted like the rest (Fig. 11's holes)
  DepthCoding depth;
  // 1 to kMaxSplatReach (micro_buffer.h); 1 here, as the kernel's tests build it, while the
  // renderer's default is MicroRenderOptions::splatReach.
  int splatReach = 1;
  // Nodes seen from behind: culled (the paper's one-sided points), or true: rasterized as the node
  // facing the other way, holding kBackFaceMicroNode (they hide what lies beyond and send nothing).
  bool backFacesOcclude = false;
};

// Nodes as the traversal reads them: sphere, cone axis, and the sine and cosine of the cone angle.
struct TraversalNode {
  Vec3 center;
  float radius = 0;
  Vec3 axis;
  float coneSin = 0, coneCos = 1;
};
static_assert(sizeof(TraversalNode) == 36, "TraversalNode is a fixed-size record");

// The hierarchy as micro-rendering reads it: the packed nodes decoded on the fly (with the cone
// codes' sines and cosines tabulated), or the float nodes with their cones' sines and cosines
// computed once per frame (with the hierarchy update).
struct MicroHierarchy {
  const PointHierarchy* hierarchy = nullptr;
  std::vector<TraversalNode> floatNodes;      // Float encoding
  float coneSin[256] = {}, coneCos[256] = {};  // Packed encoding: per cone code
  // Per node, a bound on the distance of its leaf discs from the plane through its (decoded) centre
  // normal to its axis: 0 for a leaf and for a flat node. A node's splat covers the directions that
  // meet its sphere within that slab, not the whole sphere: seen edge-on, a flat node covers a
  // sliver, and its sphere would widen the silhouette by up to a pixel.
  std::vector<float> thickness;
};
MicroHierarchy prepareMicroHierarchy(const PointHierarchy& hierarchy);

// Gather points micro-rendered together, one SIMD lane each: the CPU's counterpart of the CUDA
// threads of a warp, which the paper (3.2) keeps coherent by handing neighbouring gather points (3-D
// Morton order) to neighbouring threads. The packet walks the union of its lanes' cuts once; each lane
// meets exactly the nodes of its own cut, in the same order, so its buffer is the one it would get
// alone.
inline constexpr int kGatherPacket = 16;
static_assert(kGatherPacket < 32, "a packet's lanes are the bits of a 32-bit mask, all set as (1 << lanes) - 1");

struct MicroLane {
  const GatherPoint* gather = nullptr;
  const HemisphereMapping* mapping = nullptr;  // all lanes of a packet: the same kind, side and table size
  MicroBuffer* buffer = nullptr;
};

// Traversal, rasterization and ray casting into each lane's buffer (at most kGatherPacket lanes),
// reading the hierarchy's selected encoding. The buffers hold the nearest node per pixel afterwards.
void renderMicroBuffers(const MicroHierarchy& hierarchy, std::span<const MicroLane> lanes,
                        const MicroRenderSettings& settings, MicroCounters& counters);
// One gather point: a packet of one lane.
void renderMicroBuffer(const MicroHierarchy& hierarchy, const GatherPoint& gather, const HemisphereMapping& mapping,
                       const MicroRenderSettings& settings, MicroBuffer& buffer, MicroCounters& counters);

// The convolution: the sum over the buffer's pixels of the visible node's radiance times the pixel's
// weight. One overload per radiance layout: float RGB, or the paper's half floats (3.1).
// `directional`: the interior nodes' DirectionalRadiance (entries 1 .. n - 1), read towards the
// gather point instead of `radiance`; empty: every node sends `radiance` every way. Reads the
// buffer's pixel directions (MicroBuffer::worldX): for a buffer just rendered with this mapping.
Rgb convolveMicroBuffer(const MicroBuffer& buffer, const HemisphereMapping& mapping, std::span<const Rgb> radiance,
                        std::span<const DirectionalRadiance> directional = {});
Rgb convolveMicroBuffer(const MicroBuffer& buffer, const HemisphereMapping& mapping, std::span<const HalfRgb> radiance,
                        std::span<const DirectionalRadiance> directional = {});

}  // namespace lucent
