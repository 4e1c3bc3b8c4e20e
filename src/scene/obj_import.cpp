#include "obj_import.h"

#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <set>
#include <sstream>
#include <unordered_map>

#include "lucent/core/files.h"
#include "lucent/core/text.h"
#include "lucent/scene/loader.h"

namespace lucent::detail {
namespace fs = std::filesystem;

namespace {

[[noreturn]] void failAt(const std::string& file, int line, const std::string& what) {
  throw SceneError(file + ":" + std::to_string(line) + ": " + what);
}

std::vector<std::string> tokens(const std::string& line) {
  std::vector<std::string> out;
  std::istringstream in(line.substr(0, line.find('#')));
  for (std::string t; in >> t;) out.push_back(t);
  return out;
}

// Parses a whole token. Unlike from_chars alone it accepts a leading '+', reads values too small for a
// float as zero, and reports values too large for a float as out of range.
std::errc parseFloat(const std::string& s, float& out) {
  const char* first = s.data() + (s.size() > 1 && s[0] == '+' && s[1] != '-' ? 1 : 0);
  const char* last = s.data() + s.size();
  double d = 0;
  const auto [ptr, ec] = std::from_chars(first, last, d);
  if (ptr != last) return std::errc::invalid_argument;
  if (ec == std::errc::result_out_of_range) {
    if (s.find("e-") == std::string::npos && s.find("E-") == std::string::npos) return ec;
    d = 0;  // underflow
  } else if (ec != std::errc()) {
    return ec;
  }
  if (std::isfinite(d) && std::abs(d) > std::numeric_limits<float>::max()) return std::errc::result_out_of_range;
  out = static_cast<float>(d);
  return std::errc();
}

bool parseInt(const std::string& s, long& out) {
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
  return ec == std::errc() && ptr == s.data() + s.size();
}

std::vector<std::string> readLines(const std::string& path, const std::string& what) {
  const std::string problem = admitInputFile(path);
  if (!problem.empty()) throw SceneError(path + ": " + what + " " + problem);
  std::ifstream in(path);
  if (!in) throw SceneError(path + ": cannot open " + what);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    lines.push_back(line);
  }
  return lines;
}

// Checks that between minCount and maxCount finite numbers follow the keyword (OBJ v/vn/vt, MTL values)
// and returns them.
std::vector<float> expectNumbers(const std::string& file, int line, const std::vector<std::string>& t,
                                 size_t minCount, size_t maxCount, const std::string& expected) {
  if (t.size() - 1 < minCount || t.size() - 1 > maxCount)
    failAt(file, line, "'" + excerpt(t[0]) + "' expects " + expected + ", found " + std::to_string(t.size() - 1));
  std::vector<float> values;
  for (size_t i = 1; i < t.size(); ++i) {
    float f;
    const std::errc ec = parseFloat(t[i], f);
    if (ec == std::errc::result_out_of_range) failAt(file, line, "'" + excerpt(t[i]) + "' is out of range for a float");
    if (ec != std::errc()) failAt(file, line, "'" + excerpt(t[i]) + "' is not a number");
    if (!std::isfinite(f)) failAt(file, line, "'" + excerpt(t[0]) + "' has a non-finite value");
    if (std::abs(f) > kMaxInputMagnitude) failAt(file, line, "'" + excerpt(t[i]) + "' exceeds 1e15 in magnitude");
    values.push_back(f);
  }
  return values;
}

// An MTL file's materials in the order they are defined, each with the values Lucent reads
// (docs/scene-format.md); the defaults of an absent key are the MTL format's (Ns 1, Ni 1, illum 0).
std::vector<MaterialSpec> readMtl(const std::string& path) {
  static const std::set<std::string> colourKeys = {"Kd", "Ks", "Ke", "Tf", "Ka"};
  static const std::set<std::string> ignoredKeys = {"map_bump", "bump", "d", "Tr"};
  std::vector<MaterialSpec> materials;
  std::map<std::string, int> definitionLine;
  const auto lines = readLines(path, "material library");
  for (size_t i = 0; i < lines.size(); ++i) {
    const int line = static_cast<int>(i + 1);
    const auto t = tokens(lines[i]);
    if (t.empty()) continue;
    const std::string& key = t[0];
    if (key == "newmtl") {
      if (t.size() != 2) failAt(path, line, "'newmtl' expects one name");
      const auto [it, inserted] = definitionLine.emplace(t[1], line);
      if (!inserted)
        failAt(path, line,
               "material '" + excerpt(t[1]) + "' is defined twice (first at line " + std::to_string(it->second) + ")");
      MaterialSpec& spec = materials.emplace_back();
      spec.name = t[1];
      spec.origin = path + ":" + std::to_string(line);
      continue;
    }
    if (materials.empty()) failAt(path, line, "'" + excerpt(key) + "' before any 'newmtl'");
    MaterialSpec& spec = materials.back();
    if (colourKeys.count(key)) {
      if (t.size() == 3) failAt(path, line, "'" + excerpt(key) + "' expects 3 numbers (r g b) or 1 (grey), found 2");
      const auto v = expectNumbers(path, line, t, 1, 3, "3 numbers (r g b) or 1 (grey)");
      for (float f : v)
        if (f < 0) failAt(path, line, "'" + excerpt(key) + "' must not be negative");
      const Rgb colour = v.size() == 1 ? Rgb(v[0]) : Rgb{v[0], v[1], v[2]};
      if (key == "Kd") spec.kd = colour;
      else if (key == "Ks") spec.ks = colour;
      else if (key == "Ke") spec.ke = colour;
      else if (key == "Tf") spec.tf = colour;
    } else if (key == "Ns") {
      spec.ns = expectNumbers(path, line, t, 1, 1, "1 number")[0];
    } else if (key == "Ni") {
      spec.ni = expectNumbers(path, line, t, 1, 1, "1 number")[0];
    } else if (key == "illum") {
      const float illum = expectNumbers(path, line, t, 1, 1, "1 number")[0];
      if (illum != std::floor(illum) || illum < 0 || illum > 10)
        failAt(path, line, "'illum' expects an illumination model, an integer from 0 to 10");
      spec.illum = int(illum);
    } else if (key == "map_Kd") {
      if (t.size() != 2) failAt(path, line, "'map_Kd' expects one file name (options are not supported)");
      const fs::path texture = fs::path(path).parent_path() / t[1];
      const std::string problem = admitInputFile(texture);
      if (!problem.empty()) failAt(path, line, "texture '" + excerpt(t[1], 160) + "' " + problem);
      spec.mapKd.path = fs::absolute(texture).lexically_normal().string();
      spec.mapKd.origin = path + ":" + std::to_string(line);
    } else if (!ignoredKeys.count(key)) {
      failAt(path, line, "unknown MTL key '" + excerpt(key, 16) + "'");
    }
  }
  return materials;
}

// One vertex of a face: indices into the file's v, vt and vn lists, -1 where absent.
struct FaceVertex {
  int32_t v = -1, vt = -1, vn = -1;
  bool operator==(const FaceVertex&) const = default;
};
struct FaceVertexHash {
  size_t operator()(const FaceVertex& k) const {
    return std::hash<int64_t>()((int64_t(k.v) << 40) ^ (int64_t(k.vn) << 20) ^ k.vt);
  }
};

// Parses "v", "v/vt", "v//vn" or "v/vt/vn", each index 1-based or negative (relative to the end of
// its list so far), into 0-based indices.
FaceVertex parseFaceVertex(const std::string& file, int line, const std::string& token, const long counts[3]) {
  static const char* names[3] = {"vertex", "texture coordinate", "normal"};
  const auto malformed = [&] {
    failAt(file, line, "malformed face vertex '" + excerpt(token) + "' (expected v, v/vt, v//vn or v/vt/vn)");
  };
  std::vector<std::string> parts;
  for (size_t start = 0;;) {
    const size_t slash = token.find('/', start);
    parts.push_back(token.substr(start, slash == std::string::npos ? std::string::npos : slash - start));
    if (slash == std::string::npos) break;
    start = slash + 1;
  }
  // Only the texture coordinate of "v//vn" may be left out.
  if (parts.size() > 3 || parts[0].empty() || parts.back().empty() || (parts.size() == 2 && parts[1].empty()))
    malformed();
  int32_t index[3] = {-1, -1, -1};
  for (size_t slot = 0; slot < parts.size(); ++slot) {
    if (parts[slot].empty()) continue;
    long idx;
    if (!parseInt(parts[slot], idx) || idx == 0) malformed();
    if ((idx > 0 && idx > counts[slot]) || (idx < 0 && -idx > counts[slot]))
      failAt(file, line, "face refers to " + std::string(names[slot]) + " " + std::to_string(idx) + " but only " +
                             std::to_string(counts[slot]) + " are defined");
    index[slot] = int32_t(idx > 0 ? idx - 1 : counts[slot] + idx);
  }
  return {index[0], index[1], index[2]};
}

// The largest face that is split by ear clipping, which takes time quadratic in its vertices;
// convex faces of any size are split as a fan.
constexpr size_t kMaxNonConvexFace = 256;

// A face's triangles, as corners into `face`, covering it exactly once: triangles as they are;
// quads along their shorter diagonal unless only the other one stays inside; larger faces, in the
// plane of their Newell normal, as a fan when convex and by ear clipping otherwise. A face that
// crosses itself is refused.
void triangulateFace(const std::string& file, int line, const std::vector<Vec3>& positions,
                     const std::vector<FaceVertex>& face, std::vector<uint32_t>& corners) {
  const size_t n = face.size();
  const auto at = [&](size_t k) { return positions[size_t(face[k].v)]; };
  corners.clear();
  if (n == 3) {
    corners = {0, 1, 2};
    return;
  }
  const auto crossesItself = [&] { failAt(file, line, "the face crosses itself and cannot be split into triangles"); };
  // The face in its plane, in double precision.
  double nx = 0, ny = 0, nz = 0;
  for (size_t k = 0; k < n; ++k) {
    const Vec3 a = at(k), b = at((k + 1) % n);
    nx += (double(a.y) - b.y) * (double(a.z) + b.z);
    ny += (double(a.z) - b.z) * (double(a.x) + b.x);
    nz += (double(a.x) - b.x) * (double(a.y) + b.y);
  }
  const double nLength = std::sqrt(nx * nx + ny * ny + nz * nz);
  if (!(nLength > 0)) {
    // No area enclosed: the vertices lie on a line (a fan of zero-area triangles, all dropped) or
    // the face winds both ways around equal areas.
    for (uint32_t k = 1; k + 1 < n; ++k) {
      if (length(cross(at(k) - at(0), at(k + 1) - at(0))) > 0) crossesItself();
      corners.insert(corners.end(), {0, k, k + 1});
    }
    return;
  }
  const Frame frame(Vec3{float(nx / nLength), float(ny / nLength), float(nz / nLength)});
  struct Point {
    double x, y;
  };
  std::vector<Point> p(n);
  for (size_t k = 0; k < n; ++k) {
    const double dx = double(at(k).x) - at(0).x, dy = double(at(k).y) - at(0).y, dz = double(at(k).z) - at(0).z;
    p[k] = {dx * frame.s.x + dy * frame.s.y + dz * frame.s.z, dx * frame.t.x + dy * frame.t.y + dz * frame.t.z};
  }
  // Twice the signed area of triangle abc: positive where it winds as the face does.
  const auto turn = [&](size_t a, size_t b, size_t c) {
    return (p[b].x - p[a].x) * (p[c].y - p[a].y) - (p[b].y - p[a].y) * (p[c].x - p[a].x);
  };
  if (n == 4) {
    // The shorter diagonal first (as most OBJ readers split quads), in float as they compute it.
    const Vec3 e02 = at(2) - at(0), e13 = at(3) - at(1);
    const bool first02 = dot(e02, e02) < dot(e13, e13);
    const auto inside02 = [&] { return turn(0, 1, 2) >= 0 && turn(0, 2, 3) >= 0; };
    const auto inside13 = [&] { return turn(0, 1, 3) >= 0 && turn(1, 2, 3) >= 0; };
    if (first02 ? inside02() : !inside13() && inside02()) corners = {0, 1, 2, 0, 2, 3};
    else if (inside13()) corners = {0, 1, 3, 1, 2, 3};
    else crossesItself();
    return;
  }
  double area = 0;  // twice the face's, by the shoelace formula
  for (size_t k = 0; k < n; ++k) area += p[k].x * p[(k + 1) % n].y - p[(k + 1) % n].x * p[k].y;
  // Convex up to rounding: every corner turns the face's way, or runs on nearly straight, straying
  // by less than a thousandth of a radian (the corners of a finely tessellated circle, written as
  // floats, do). A corner that turns back on itself (a narrow notch's tip) has as small a sine, but
  // is the sharpest of reflex corners.
  bool convex = true;
  for (size_t k = 0; k < n && convex; ++k) {
    const size_t a = (k + n - 1) % n, c = (k + 1) % n;
    const double ea = std::hypot(p[k].x - p[a].x, p[k].y - p[a].y), ec = std::hypot(p[c].x - p[k].x, p[c].y - p[k].y);
    const double onward = (p[k].x - p[a].x) * (p[c].x - p[k].x) + (p[k].y - p[a].y) * (p[c].y - p[k].y);
    convex = turn(a, k, c) >= 0 || (onward > 0 && turn(a, k, c) >= -1e-3 * ea * ec);
  }
  if (convex) {
    for (uint32_t k = 1; k + 1 < n; ++k) corners.insert(corners.end(), {0, k, k + 1});
  } else {
    if (n > kMaxNonConvexFace)
      failAt(file, line, "a non-convex face with " + std::to_string(n) + " vertices (at most " +
                             std::to_string(kMaxNonConvexFace) + "; split it into smaller faces)");
    std::vector<uint32_t> left(n);
    for (uint32_t k = 0; k < n; ++k) left[k] = k;
    const auto coincide = [&](uint32_t a, uint32_t b) { return p[a].x == p[b].x && p[a].y == p[b].y; };
    const auto inside = [&](uint32_t a, uint32_t b, uint32_t c, uint32_t q) {
      return turn(a, b, q) >= 0 && turn(b, c, q) >= 0 && turn(c, a, q) >= 0;
    };
    while (left.size() > 3) {
      const size_t m = left.size();
      size_t ear = m;
      for (size_t k = 0; k < m && ear == m; ++k) {
        const uint32_t a = left[(k + m - 1) % m], b = left[k], c = left[(k + 1) % m];
        if (!(turn(a, b, c) > 0)) continue;
        bool empty = true;
        for (size_t j = 0; j < m && empty; ++j) {
          const uint32_t q = left[j];
          empty = coincide(q, a) || coincide(q, b) || coincide(q, c) || !inside(a, b, c, q);
        }
        if (empty) ear = k;
      }
      // No proper ear: a corner where the boundary runs straight on is cut off as a zero-area
      // triangle (dropped as degenerate).
      for (size_t k = 0; k < m && ear == m; ++k)
        if (turn(left[(k + m - 1) % m], left[k], left[(k + 1) % m]) == 0) ear = k;
      if (ear == m) crossesItself();
      corners.insert(corners.end(), {left[(ear + m - 1) % m], left[ear], left[(ear + 1) % m]});
      left.erase(left.begin() + std::ptrdiff_t(ear));
    }
    corners.insert(corners.end(), left.begin(), left.end());
  }
  // The triangles cover the face once exactly when their areas add up to the face's; on a face
  // that crosses itself, the shoelace formula subtracts the parts that wind the other way.
  double covered = 0;
  for (size_t c = 0; c < corners.size(); c += 3) covered += std::abs(turn(corners[c], corners[c + 1], corners[c + 2]));
  if (std::abs(covered - area) > 1e-4 * covered) crossesItself();
}

}  // namespace

void importObj(const std::string& objPath, Scene& scene, ObjImport& import) {
  const auto lines = readLines(objPath, "OBJ file");
  std::vector<Vec3> positions, normals;
  std::vector<Vec2> texcoords;
  std::unordered_map<FaceVertex, uint32_t, FaceVertexHash> vertexOf;
  // The scene's vertex for a face vertex, shared by every face that names the same three indices.
  const auto sceneVertex = [&](const FaceVertex& fv) {
    const auto [it, inserted] = vertexOf.emplace(fv, static_cast<uint32_t>(scene.positions.size()));
    if (inserted) {
      scene.positions.push_back(positions[size_t(fv.v)]);
      Vec3 n{0, 0, 0};
      if (fv.vn >= 0) {
        n = normals[size_t(fv.vn)];
        const float len = length(n);
        n = len > 0 ? n / len : Vec3{0, 0, 0};
      }
      scene.normals.push_back(n);
      scene.texcoords.push_back(fv.vt >= 0 ? texcoords[size_t(fv.vt)] : Vec2{0, 0});
    }
    return it->second;
  };
  // Faces without a material get a neutral diffuse one, created on first use.
  const auto defaultMaterial = [&]() -> uint32_t {
    auto [it, inserted] = import.materialIndex.emplace("(default)", static_cast<uint32_t>(import.specs.size()));
    if (inserted) {
      MaterialSpec spec;
      spec.name = "(default)";
      spec.kd = Rgb(0.5f);
      spec.origin = objPath;
      import.specs.push_back(spec);
    }
    return it->second;
  };

  std::set<std::string> libraryMaterials;  // defined by this file's mtllib statements so far
  std::optional<uint32_t> material;
  std::vector<FaceVertex> face;
  std::vector<uint32_t> corners;
  for (size_t i = 0; i < lines.size(); ++i) {
    const int line = static_cast<int>(i + 1);
    const auto t = tokens(lines[i]);
    if (t.empty()) continue;
    const std::string& key = t[0];
    if (key == "v") {
      const auto v = expectNumbers(objPath, line, t, 3, 3, "3 numbers");
      positions.push_back({v[0], v[1], v[2]});
    } else if (key == "vn") {
      const auto v = expectNumbers(objPath, line, t, 3, 3, "3 numbers");
      normals.push_back({v[0], v[1], v[2]});
    } else if (key == "vt") {
      const auto v = expectNumbers(objPath, line, t, 2, 3, "2 or 3 numbers");
      texcoords.push_back({v[0], v[1]});
    } else if (key == "f") {
      if (t.size() < 4) failAt(objPath, line, "a face needs at least 3 vertices");
      const long counts[3] = {long(positions.size()), long(texcoords.size()), long(normals.size())};
      face.clear();
      for (size_t k = 1; k < t.size(); ++k) face.push_back(parseFaceVertex(objPath, line, t[k], counts));
      triangulateFace(objPath, line, positions, face, corners);
      const uint32_t materialId = material ? *material : defaultMaterial();
      for (size_t c = 0; c < corners.size(); c += 3) {
        const FaceVertex& a = face[corners[c]];
        const FaceVertex& b = face[corners[c + 1]];
        const FaceVertex& d = face[corners[c + 2]];
        const Vec3 p0 = positions[size_t(a.v)];
        if (!(length(cross(positions[size_t(b.v)] - p0, positions[size_t(d.v)] - p0)) > 0)) {
          ++scene.droppedDegenerateTriangles;
          continue;
        }
        for (const FaceVertex* fv : {&a, &b, &d}) scene.indices.push_back(sceneVertex(*fv));
        scene.materialIds.push_back(materialId);
      }
    } else if (key == "mtllib") {
      if (t.size() < 2) failAt(objPath, line, "'mtllib' expects a file name");
      for (size_t k = 1; k < t.size(); ++k) {
        const fs::path mtl = fs::path(objPath).parent_path() / t[k];
        const std::string problem = admitInputFile(mtl);
        if (!problem.empty()) failAt(objPath, line, "material library '" + excerpt(t[k], 160) + "' " + problem);
        import.libraries.push_back(mtl.string());
        // The first definition of a name, in this file or an earlier one, is the material.
        for (MaterialSpec& spec : readMtl(mtl.string())) {
          libraryMaterials.insert(spec.name);
          if (import.materialIndex.emplace(spec.name, static_cast<uint32_t>(import.specs.size())).second)
            import.specs.push_back(std::move(spec));
        }
      }
    } else if (key == "usemtl") {
      if (t.size() != 2) failAt(objPath, line, "'usemtl' expects one material name");
      if (!libraryMaterials.count(t[1]))
        failAt(objPath, line, "material '" + excerpt(t[1]) + "' is not defined in a material library named before it");
      material = import.materialIndex.at(t[1]);
    } else if (key != "o" && key != "g" && key != "s") {
      failAt(objPath, line, "unsupported OBJ statement '" + excerpt(key, 16) + "'");
    }
  }
}

Material classifyMaterial(const MaterialSpec& spec) {
  const auto fail = [&](const std::string& what) {
    throw SceneError(spec.origin + ": material '" + spec.name + "': " + what);
  };
  Material m;
  m.kd = spec.kd;
  m.ks = spec.ks;
  m.ke = spec.ke;
  m.ns = spec.ns;
  m.ni = spec.ni;
  m.metallic = spec.metallic;
  m.roughness = spec.roughness;
  m.masking = spec.masking;
  m.sheenColour = spec.sheenColour;
  m.sheenRoughness = spec.sheenRoughness;
  m.clearcoat = spec.clearcoat;
  m.clearcoatRoughness = spec.clearcoatRoughness;
  m.clearcoatNormalScale = spec.clearcoatNormalScale;
  m.transmission = spec.transmission;
  m.boundsVolume = spec.boundsVolume ? 1 : 0;
  m.attenuationColour = spec.attenuationColour;
  m.attenuationDistance = spec.attenuationDistance;
  m.specular = spec.specular;
  m.normalScale = spec.normalScale;
  m.alphaMode = spec.alphaMode;
  m.alphaCutoff = spec.alphaCutoff;
  m.baseAlpha = spec.baseAlpha;
  if (spec.type) {
    m.type = *spec.type;
  } else {
    const bool refracts = spec.illum == 4 || spec.illum == 6 || spec.illum == 7 || spec.illum == 9 ||
                          (!spec.tf.isBlack() && spec.ni != 1.0f);
    const bool reflects = spec.illum == 3 || spec.illum == 5 || spec.illum == 8 ||
                          (spec.kd.isBlack() && !spec.ks.isBlack() && spec.ns >= 1000.0f);
    m.type = refracts   ? MaterialType::Glass
             : reflects ? MaterialType::Mirror
             : !spec.ks.isBlack() ? MaterialType::Phong
                                  : MaterialType::Diffuse;
  }
  for (int c = 0; c < 3; ++c) {
    if (!(spec.kd[c] >= 0) || !(spec.ks[c] >= 0) || !(spec.ke[c] >= 0) || !std::isfinite(spec.ke[c]))
      fail("Kd, Ks and Ke must be finite and non-negative");
  }
  switch (m.type) {
    case MaterialType::Diffuse:
      m.ks = Rgb(0.0f);
      [[fallthrough]];
    case MaterialType::Phong:
      for (int c = 0; c < 3; ++c)
        if (m.kd[c] + m.ks[c] > 1.0f + 1e-6f) fail("Kd + Ks exceeds 1 (the material would create energy)");
      if (!(m.ns >= 0) || !std::isfinite(m.ns)) fail("Ns must be finite and non-negative");
      break;
    case MaterialType::Mirror:
      if (spec.ks.maxComponent() > 1.0f) fail("mirror reflectance Ks exceeds 1");
      m.kd = Rgb(0.0f);
      break;
    case MaterialType::Gltf:
      // The glTF import checks each value against its JSON path; these are the model's own bounds.
      if (!(spec.kd.maxComponent() <= 1) || !(m.metallic >= 0 && m.metallic <= 1) ||
          !(m.roughness >= 0 && m.roughness <= 1) || !(m.specular >= 0 && m.specular <= 1) || !(m.ni >= 0) ||
          !std::isfinite(m.ni) || !std::isfinite(m.ks.maxComponent()) || !(m.sheenColour.maxComponent() <= 1) ||
          !(std::min({m.sheenColour.r, m.sheenColour.g, m.sheenColour.b}) >= 0) || !(m.sheenRoughness >= 0 && m.sheenRoughness <= 1) ||
          !(m.clearcoat >= 0 && m.clearcoat <= 1) || !(m.clearcoatRoughness >= 0 && m.clearcoatRoughness <= 1) ||
          !std::isfinite(m.clearcoatNormalScale) || !(m.transmission >= 0 && m.transmission <= 1) ||
          !(std::min({m.attenuationColour.r, m.attenuationColour.g, m.attenuationColour.b}) >= 0) ||
          !(m.attenuationColour.maxComponent() <= 1) || !(m.attenuationDistance > 0))
        fail("glTF parameters out of their ranges");
      break;
    case MaterialType::Glass:
      if (!(m.ni > 0) || !std::isfinite(m.ni) || m.ni == 1.0f)
        fail("glass needs an index of refraction Ni > 0 other than 1 (index 1 is invisible; the MTL default)");
      m.kd = Rgb(0.0f);
      m.ks = Rgb(0.0f);
      break;
  }
  return m;
}

}  // namespace lucent::detail
