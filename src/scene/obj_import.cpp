#include "obj_import.h"

#include <tiny_obj_loader.h>

#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>
#include <unordered_map>

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
  if (!fs::is_regular_file(path)) throw SceneError(path + ": " + what + " is not a regular file");
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
    failAt(file, line, "'" + t[0] + "' expects " + expected + ", found " + std::to_string(t.size() - 1));
  std::vector<float> values;
  for (size_t i = 1; i < t.size(); ++i) {
    float f;
    const std::errc ec = parseFloat(t[i], f);
    if (ec == std::errc::result_out_of_range) failAt(file, line, "'" + t[i] + "' is out of range for a float");
    if (ec != std::errc()) failAt(file, line, "'" + t[i] + "' is not a number");
    if (!std::isfinite(f)) failAt(file, line, "'" + t[0] + "' has a non-finite value");
    if (std::abs(f) > kMaxInputMagnitude) failAt(file, line, "'" + t[i] + "' exceeds 1e15 in magnitude");
    values.push_back(f);
  }
  return values;
}

struct MtlScan {
  std::map<std::string, int> definitionLine;
  // Colours as we read them: tinyobjloader reads "Kd 0.5" as (0.5, 0, 0), the MTL format as grey.
  std::map<std::string, std::map<std::string, Rgb>> colours;
};

// MTL keys Lucent understands, and those it accepts but ignores (docs/scene-format.md).
MtlScan scanMtl(const std::string& path) {
  static const std::set<std::string> colourKeys = {"Kd", "Ks", "Ke", "Tf", "Ka"};
  static const std::set<std::string> scalarKeys = {"Ns", "Ni", "illum", "d", "Tr"};
  static const std::set<std::string> ignoredKeys = {"map_bump", "bump"};
  MtlScan scan;
  const auto lines = readLines(path, "material library");
  std::string material;
  for (size_t i = 0; i < lines.size(); ++i) {
    const int line = static_cast<int>(i + 1);
    const auto t = tokens(lines[i]);
    if (t.empty()) continue;
    const std::string& key = t[0];
    if (key == "newmtl") {
      if (t.size() != 2) failAt(path, line, "'newmtl' expects one name");
      const auto [it, inserted] = scan.definitionLine.emplace(t[1], line);
      if (!inserted)
        failAt(path, line,
               "material '" + t[1] + "' is defined twice (first at line " + std::to_string(it->second) + ")");
      material = t[1];
      continue;
    }
    if (material.empty()) failAt(path, line, "'" + key + "' before any 'newmtl'");
    if (colourKeys.count(key)) {
      if (t.size() == 3) failAt(path, line, "'" + key + "' expects 3 numbers (r g b) or 1 (grey), found 2");
      const auto v = expectNumbers(path, line, t, 1, 3, "3 numbers (r g b) or 1 (grey)");
      for (float f : v)
        if (f < 0) failAt(path, line, "'" + key + "' must not be negative");
      scan.colours[material][key] = v.size() == 1 ? Rgb(v[0]) : Rgb{v[0], v[1], v[2]};
    } else if (scalarKeys.count(key)) {
      expectNumbers(path, line, t, 1, 1, "1 number");
    } else if (key == "map_Kd") {
      if (t.size() != 2) failAt(path, line, "'map_Kd' expects one file name (options are not supported)");
      if (!fs::is_regular_file(fs::path(path).parent_path() / t[1]))
        failAt(path, line, "texture '" + t[1] + "' not found");
    } else if (!ignoredKeys.count(key)) {
      failAt(path, line, "unknown MTL key '" + key + "'");
    }
  }
  return scan;
}

struct ObjScan {
  std::map<std::string, std::string> materialOrigin;  // name -> "file.mtl:line" (first definition wins)
  std::map<std::string, std::map<std::string, Rgb>> colours;
};

// Validates the OBJ statements Lucent reads, and the material libraries they name, with line numbers
// tinyobjloader cannot give.
ObjScan scanObj(const std::string& path) {
  const auto lines = readLines(path, "OBJ file");
  long nv = 0, nvt = 0, nvn = 0;
  ObjScan scan;
  for (size_t i = 0; i < lines.size(); ++i) {
    const int line = static_cast<int>(i + 1);
    const auto t = tokens(lines[i]);
    if (t.empty()) continue;
    const std::string& key = t[0];
    if (key == "v") {
      expectNumbers(path, line, t, 3, 3, "3 numbers");
      ++nv;
    } else if (key == "vn") {
      expectNumbers(path, line, t, 3, 3, "3 numbers");
      ++nvn;
    } else if (key == "vt") {
      expectNumbers(path, line, t, 2, 3, "2 or 3 numbers");
      ++nvt;
    } else if (key == "f") {
      if (t.size() < 4) failAt(path, line, "a face needs at least 3 vertices");
      for (size_t k = 1; k < t.size(); ++k) {
        std::string part;
        std::istringstream refs(t[k]);
        const long counts[3] = {nv, nvt, nvn};
        const char* names[3] = {"vertex", "texture coordinate", "normal"};
        for (int slot = 0; std::getline(refs, part, '/'); ++slot) {
          if (slot > 2) failAt(path, line, "malformed face vertex '" + t[k] + "'");
          if (part.empty() && slot > 0) continue;
          long idx;
          if (!parseInt(part, idx) || idx == 0) failAt(path, line, "malformed face vertex '" + t[k] + "'");
          if ((idx > 0 && idx > counts[slot]) || (idx < 0 && -idx > counts[slot]))
            failAt(path, line, "face refers to " + std::string(names[slot]) + " " + std::to_string(idx) +
                                   " but only " + std::to_string(counts[slot]) + " are defined");
        }
      }
    } else if (key == "mtllib") {
      if (t.size() < 2) failAt(path, line, "'mtllib' expects a file name");
      for (size_t k = 1; k < t.size(); ++k) {
        const fs::path mtl = fs::path(path).parent_path() / t[k];
        if (!fs::is_regular_file(mtl)) failAt(path, line, "material library '" + t[k] + "' not found");
        const MtlScan mtlScan = scanMtl(mtl.string());
        for (const auto& [name, defLine] : mtlScan.definitionLine)
          if (scan.materialOrigin.emplace(name, mtl.string() + ":" + std::to_string(defLine)).second &&
              mtlScan.colours.count(name))
            scan.colours[name] = mtlScan.colours.at(name);
      }
    } else if (key == "usemtl") {
      // tinyobjloader would give faces of an undefined material no material, silently.
      if (t.size() != 2) failAt(path, line, "'usemtl' expects one material name");
      if (!scan.materialOrigin.count(t[1]))
        failAt(path, line, "material '" + t[1] + "' is not defined in a material library named before it");
    } else if (key != "o" && key != "g" && key != "s") {
      failAt(path, line, "unsupported OBJ statement '" + key + "'");
    }
  }
  return scan;
}

Rgb toRgb(const float v[3]) { return {v[0], v[1], v[2]}; }

}  // namespace

void importObj(const std::string& objPath, Scene& scene, ObjImport& import) {
  const ObjScan scan = scanObj(objPath);

  tinyobj::ObjReaderConfig config;
  config.triangulate = true;
  config.vertex_color = false;
  tinyobj::ObjReader reader;
  if (!reader.ParseFromFile(objPath, config)) throw SceneError(objPath + ": " + reader.Error());
  const auto& attrib = reader.GetAttrib();
  const auto& materials = reader.GetMaterials();
  const fs::path objDir = fs::path(objPath).parent_path();

  // Map this file's material ids onto the scene-wide list (first definition of a name wins).
  std::vector<uint32_t> materialMap(materials.size());
  for (size_t m = 0; m < materials.size(); ++m) {
    const auto& mat = materials[m];
    auto [it, inserted] = import.materialIndex.emplace(mat.name, static_cast<uint32_t>(import.specs.size()));
    materialMap[m] = it->second;
    if (!inserted) continue;
    MaterialSpec spec;
    spec.name = mat.name;
    spec.kd = toRgb(mat.diffuse);
    spec.ks = toRgb(mat.specular);
    spec.ke = toRgb(mat.emission);
    spec.tf = toRgb(mat.transmittance);
    spec.ns = mat.shininess;
    spec.ni = mat.ior;
    spec.illum = mat.illum;
    const auto colours = scan.colours.find(mat.name);
    if (colours != scan.colours.end()) {
      const auto& c = colours->second;
      for (auto [key, value] : {std::pair{"Kd", &spec.kd}, {"Ks", &spec.ks}, {"Ke", &spec.ke}, {"Tf", &spec.tf}})
        if (c.count(key)) *value = c.at(key);
    }
    const auto origin = scan.materialOrigin.find(mat.name);
    spec.origin = origin != scan.materialOrigin.end() ? origin->second : objPath;
    if (!mat.diffuse_texname.empty()) {
      const auto mtlDir = fs::path(spec.origin.substr(0, spec.origin.rfind(':'))).parent_path();
      spec.mapKd = fs::absolute(mtlDir / mat.diffuse_texname).lexically_normal().string();
    }
    import.specs.push_back(spec);
  }

  // Faces without a material get a neutral diffuse one, created on first use.
  auto defaultMaterial = [&]() -> uint32_t {
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

  struct KeyHash {
    size_t operator()(const std::tuple<int, int, int>& k) const {
      return std::hash<int64_t>()((int64_t(std::get<0>(k)) << 40) ^ (int64_t(std::get<1>(k)) << 20) ^
                                  std::get<2>(k));
    }
  };
  std::unordered_map<std::tuple<int, int, int>, uint32_t, KeyHash> vertexOf;
  auto vertexIndex = [&](const tinyobj::index_t& idx) {
    const auto key = std::make_tuple(idx.vertex_index, idx.normal_index, idx.texcoord_index);
    auto [it, inserted] = vertexOf.emplace(key, static_cast<uint32_t>(scene.positions.size()));
    if (inserted) {
      const float* p = &attrib.vertices[3 * idx.vertex_index];
      scene.positions.push_back({p[0], p[1], p[2]});
      Vec3 n{0, 0, 0};
      if (idx.normal_index >= 0) {
        const float* q = &attrib.normals[3 * idx.normal_index];
        n = {q[0], q[1], q[2]};
        const float len = length(n);
        n = len > 0 ? n / len : Vec3{0, 0, 0};
      }
      scene.normals.push_back(n);
      Vec2 uv{0, 0};
      if (idx.texcoord_index >= 0) uv = {attrib.texcoords[2 * idx.texcoord_index],
                                         attrib.texcoords[2 * idx.texcoord_index + 1]};
      scene.texcoords.push_back(uv);
    }
    return it->second;
  };

  for (const auto& shape : reader.GetShapes()) {
    const auto& mesh = shape.mesh;
    for (size_t f = 0; f < mesh.num_face_vertices.size(); ++f) {
      const tinyobj::index_t* idx = &mesh.indices[3 * f];
      auto pos = [&](int k) {
        const float* p = &attrib.vertices[3 * idx[k].vertex_index];
        return Vec3{p[0], p[1], p[2]};
      };
      const Vec3 p0 = pos(0);
      const Vec3 e = cross(pos(1) - p0, pos(2) - p0);
      if (!(length(e) > 0)) {
        ++scene.droppedDegenerateTriangles;
        continue;
      }
      for (int k = 0; k < 3; ++k) scene.indices.push_back(vertexIndex(idx[k]));
      const int m = mesh.material_ids[f];
      scene.materialIds.push_back(m >= 0 ? materialMap[m] : defaultMaterial());
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
