#include "lucent/scene/loader.h"

#include <cfloat>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <iterator>
#include <set>
#include <span>
#include <nlohmann/json.hpp>

#include "json_fields.h"
#include "lucent/core/files.h"
#include "lucent/core/text.h"
#include "lucent/image/image.h"
#include "lucent/scene/bsdf.h"
#include "lucent/scene/texture.h"
#include "gltf_import.h"
#include "obj_import.h"

namespace lucent {
namespace fs = std::filesystem;
using detail::JsonFields;

namespace {

// Reads an RGB (or grey) image into texels, convert(channel values as stored, then alpha, 1 where the
// image has none; sRGB-encoded or not) giving each; row 0 is the top row.
// Negative values are refused unless allowNegative (the caller checks them).
// `read` reads the image named `path` (a file, or an image held in memory named as one). `srgb`:
// sRGB-encoded whatever the file's metadata says (glTF's colour textures), else as it says.
template <class Convert>
auto readImageTexels(const std::string& path, const std::string& context, uint32_t& w, uint32_t& h, Convert convert,
                     bool allowNegative = false,
                     const std::function<Image(ImageMetadata*)>& read = {}, bool srgbWhateverItSays = false) {
  Image image;
  ImageMetadata metadata;
  try {
    image = read ? read(&metadata) : readImage(path, &metadata);
  } catch (const std::exception& e) {
    throw SceneError(context + ": " + e.what());  // the message names the image
  }
  w = static_cast<uint32_t>(image.width());
  h = static_cast<uint32_t>(image.height());
  const int nc = image.channelCount();
  if (nc < 1 || w == 0 || h == 0) throw SceneError(context + ": image '" + path + "' is empty");
  const bool srgb = srgbWhateverItSays || isSrgbEncoded(path, metadata);
  const int alpha = image.channelIndex("A");
  std::vector<decltype(convert(static_cast<const float*>(nullptr), srgb))> texels(size_t(w) * h);
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x) {
      float stored[4];
      stored[3] = alpha >= 0 ? std::clamp(image.at(int(x), int(y), alpha), 0.0f, 1.0f) : 1.0f;
      for (int k = 0; k < 3; ++k) {
        const float v = stored[k] = image.at(int(x), int(y), nc >= 3 ? k : 0);
        // The linear value must be finite and not negative; for sRGB values in [0, 1] it is.
        const bool valid =
            std::isfinite(v) && (v >= 0 || allowNegative) && (!srgb || v <= 1 || std::isfinite(srgbToLinear(v)));
        if (!valid) throw SceneError(context + ": image '" + path + "' has negative or non-finite texels");
      }
      texels[size_t(y) * w + x] = convert(stored, srgb);
    }
  return texels;
}

// Linear texels (environment maps). Lossy compression leaves some texels of real HDR maps slightly
// negative (Poly Haven's courtyard: 1,818 texels down to -0.0032, envmaps/SOURCE.txt): those within
// 1% of the map's mean value below 0 are clamped to 0 and counted in `clamped`, with the most negative
// in `mostNegative`; a map with any texel further below 0 is refused.
std::vector<Rgb> readTexels(const std::string& path, const std::string& context, uint32_t& w, uint32_t& h,
                            uint32_t& clamped, float& mostNegative) {
  std::vector<Rgb> texels = readImageTexels(
      path, context, w, h,
      [](const float* stored, bool srgb) {
        Rgb c;
        for (int k = 0; k < 3; ++k) c[k] = srgb ? srgbToLinear(stored[k]) : stored[k];
        return c;
      },
      true);
  double sum = 0;
  mostNegative = 0;
  for (const Rgb& t : texels)
    for (int k = 0; k < 3; ++k) sum += std::abs(t[k]), mostNegative = std::min(mostNegative, t[k]);
  const double meanMagnitude = sum / (3.0 * double(texels.size()));
  if (mostNegative < 0 && !(double(-mostNegative) <= 0.01 * meanMagnitude))
    throw SceneError(context + ": image '" + path + "' has negative texels, down to " + std::to_string(mostNegative) +
                     ", more than 1% of its texels' mean magnitude (" + std::to_string(meanMagnitude) +
                     ") below 0");
  clamped = 0;
  for (Rgb& t : texels)
    if (t.r < 0 || t.g < 0 || t.b < 0) {
      ++clamped;
      for (int k = 0; k < 3; ++k) t[k] = std::max(t[k], 0.0f);
    }
  return texels;
}

// 8-bit sRGB texels packed as R | G << 8 | B << 16 | A << 24 (diffuse albedo maps; A linear, 255
// where the image has no alpha). An 8-bit
// sRGB file's values are its codes over 255 (to a rounding of the reader's) and are kept as they
// are, which decoding to linear and encoding back would give too; other values are converted to
// linear, clamped to [0, 1] (reflectance) and encoded.
std::vector<uint32_t> readSrgb8Texels(const std::string& path, const std::string& context, uint32_t& w, uint32_t& h,
                                      const std::function<Image(ImageMetadata*)>& read = {},
                                      bool srgbWhateverItSays = false) {
  return readImageTexels(path, context, w, h, [](const float* stored, bool srgb) {
    uint32_t packed = uint32_t(std::lround(255.0f * stored[3])) << 24;
    for (int k = 0; k < 3; ++k) {
      const float v = stored[k];
      const long code = std::lround(255.0f * v);
      uint32_t byte;
      if (srgb && code >= 0 && code <= 255 && std::abs(255.0f * v - float(code)) < 1e-3f) {
        byte = uint32_t(code);
      } else {
        const float linear = srgb ? srgbToLinear(v) : v;
        byte = linearToSrgb8(std::clamp(linear, 0.0f, 1.0f));
      }
      packed |= byte << (8 * k);
    }
    return packed;
  }, false, read, srgbWhateverItSays);
}

// 8-bit linear texels packed as readSrgb8Texels packs them (glTF's data textures: metallic and
// roughness, normals, the specular factor in A): each stored value in [0, 1] to its nearest code,
// whatever colour space the file declares, since glTF defines these channels as linear values.
std::vector<uint32_t> readUnorm8Texels(const std::string& path, const std::string& context, uint32_t& w, uint32_t& h,
                                       const std::function<Image(ImageMetadata*)>& read) {
  return readImageTexels(path, context, w, h, [](const float* stored, bool) {
    uint32_t packed = 0;
    for (int k = 0; k < 4; ++k) packed |= uint32_t(std::lround(255.0f * std::clamp(stored[k], 0.0f, 1.0f))) << (8 * k);
    return packed;
  }, false, read);
}

// The share of a normal texture's texels that tilt the normal more than 45 degrees from the
// surface's. A height (bump) map stored as a normal texture tilts most of them: its grey codes
// decode to equal x, y and z, (0.8, 0.8, 0.8) to a tilt of 55 degrees. Blender's OBJ importer turns
// map_Bump into a normal texture so, and the glTF it exports carries it.
double steepNormalShare(std::span<const uint32_t> texels) {
  if (texels.empty()) return 0;
  size_t steep = 0;
  for (const uint32_t t : texels) {
    float n[3];
    for (int k = 0; k < 3; ++k) n[k] = float((t >> (8 * k)) & 0xffu) * (2.0f / 255.0f) - 1.0f;
    steep += n[2] <= 0 || 2 * n[2] * n[2] < n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
  }
  return double(steep) / double(texels.size());
}

std::string resolve(const fs::path& base, const std::string& relative) {
  return (base / relative).lexically_normal().string();
}

// The file a JSON key names must exist and be a regular file (a directory opens, then reads as empty).
void requireFile(const JsonFields& fields, const std::string& key, const std::string& path) {
  const std::string problem = admitInputFile(path);
  if (!problem.empty()) fields.failKey(key, "file '" + path + "' " + problem);
}

void loadCamera(JsonFields camera, Scene& scene) {
  Camera& c = scene.camera;
  c.eye = camera.vec3("eye");
  c.lookAt = camera.vec3("look_at");
  c.up = camera.vec3("up");
  c.fovY = camera.number("fov_y");
  if (!(c.fovY > 0 && c.fovY < 180)) camera.failKey("fov_y", "must be between 0 and 180 degrees (exclusive)");
  if (!(length(c.lookAt - c.eye) > 0)) camera.failKey("look_at", "must differ from eye");
  if (!(length(cross(c.up, c.lookAt - c.eye)) > 0)) camera.failKey("up", "must not be parallel to the view direction");
  const auto& res = camera.raw("resolution");
  if (!res.is_array() || res.size() != 2 || !res[0].is_number_integer() || !res[1].is_number_integer() ||
      res[0].get<long>() < 1 || res[1].get<long>() < 1 || res[0].get<long>() > kMaxImageSide || res[1].get<long>() > kMaxImageSide)
    camera.failKey("resolution", "expected [width, height], positive integers up to 65536");
  c.width = res[0].get<int>();
  c.height = res[1].get<int>();
  if (uint64_t(c.width) * c.height > kMaxImagePixels)
    camera.failKey("resolution", "more than 2^26 pixels (the render buffers would not fit in memory)");
  camera.finish();
}

void applyMaterialOverride(JsonFields fields, detail::MaterialSpec& spec, const fs::path& base) {
  spec.origin = fields.file() + ": " + fields.keyPath("");
  spec.origin.pop_back();  // the trailing '.'
  if (fields.has("type")) {
    const std::string type = fields.string("type");
    spec.type = sceneFileMaterialType(type);
    if (!spec.type) fields.failKey("type", "expected one of " + sceneFileMaterialTypes());
  }
  if (fields.has("Kd")) spec.kd = fields.rgb("Kd");
  if (fields.has("Ks")) spec.ks = fields.rgb("Ks");
  if (fields.has("Ke")) spec.ke = fields.rgb("Ke");
  if (fields.has("double_sided")) {
    spec.doubleSided = fields.boolean("double_sided");
    spec.singleSided = spec.singleSided && !spec.doubleSided;  // true makes a glTF material two-sided
  }
  if (fields.has("Ns")) spec.ns = fields.number("Ns");
  if (fields.has("Ni")) spec.ni = fields.number("Ni");
  if (fields.has("map_Kd")) {
    spec.mapKd.path = resolve(base, fields.string("map_Kd"));
    spec.mapKd.origin = fields.file() + ": " + fields.keyPath("map_Kd");
    requireFile(fields, "map_Kd", spec.mapKd.path);
  }
  fields.finish();
}

void loadLight(JsonFields light, Scene& scene, const fs::path& base) {
  const std::string type = light.string("type");
  if (type == "point") {
    Light l;
    l.type = LightType::Point;
    l.vector = light.vec3("position");
    l.value = light.rgb("power") / (4.0f * kPi);  // isotropic: intensity = power / 4 pi
    scene.lights.push_back(l);
  } else if (type == "directional") {
    Light l;
    l.type = LightType::Directional;
    const Vec3 d = light.vec3("direction");
    if (!(length(d) > 0)) light.failKey("direction", "must not be zero");
    l.vector = normalize(d);
    l.value = light.rgb("irradiance");
    scene.lights.push_back(l);
  } else if (type == "environment") {
    Environment& env = scene.environment;
    if (env.present) light.fail("only one environment light is allowed");
    env.present = true;
    if (light.has("map")) {
      env.source = resolve(base, light.string("map"));
      requireFile(light, "map", env.source);
      scene.inputFiles.push_back(env.source);
      const float scale = light.number("scale", 1.0f);
      if (!(scale >= 0)) light.failKey("scale", "must not be negative");
      env.texels = readTexels(env.source, light.file() + ": " + light.keyPath("map"), env.width, env.height,
                              env.clampedTexels, env.mostNegativeTexel);
      for (Rgb& t : env.texels) {
        t *= scale;
        if (!isFinite(t)) light.failKey("scale", "makes the map's radiance overflow");
      }
      std::vector<float> weights(env.texels.size());
      for (uint32_t y = 0; y < env.height; ++y) {
        const float sinTheta = std::sin(kPi * (y + 0.5f) / env.height);
        for (uint32_t x = 0; x < env.width; ++x)
          weights[size_t(y) * env.width + x] = env.texels[size_t(y) * env.width + x].luminance() * sinTheta;
      }
      try {
        env.distribution = Distribution2D(weights, env.width, env.height);
      } catch (const std::invalid_argument&) {
        light.failKey("scale", "makes the map's total radiance overflow");
      }
    } else {
      env.radiance = light.rgb("radiance");
    }
  } else {
    light.failKey("type", "expected one of point, directional, environment");
  }
  light.finish();
}

// "line L, column C" of byte `offset` of `text`.
std::string positionOf(const std::string& text, size_t offset) {
  size_t line = 1, column = 1;
  for (size_t i = 0; i < offset && i < text.size(); ++i) {
    if (text[i] == '\n') ++line, column = 1;
    else ++column;
  }
  return "line " + std::to_string(line) + ", column " + std::to_string(column);
}

// The scene file's JSON. Refuses what nlohmann::json would take silently: a key given twice in one
// object (the second value would win unseen), naming the key's path.
nlohmann::json parseSceneJson(const std::string& text, const std::string& path) {
  // The open objects and arrays: how each is named in its parent (".key" or "[i]"), the keys an
  // object has had, the elements an array has had.
  struct Open {
    std::string name;
    bool array = false;
    std::set<std::string> keys;
    size_t elements = 0;
  };
  std::vector<Open> open;
  std::string pendingKey;
  // The name of the value that starts now in the innermost open container.
  const auto nameOfNext = [&]() -> std::string {
    if (open.empty()) return "";
    // Appended rather than "[" + ...: GCC 12 warns falsely of overlapping copies there (-Wrestrict).
    std::string name = open.back().array ? "[" : open.size() > 1 ? "." : "";
    if (open.back().array) return name.append(std::to_string(open.back().elements++)).append("]");
    return name.append(excerpt(pendingKey));
  };
  const nlohmann::json::parser_callback_t checkKeys = [&](int, nlohmann::json::parse_event_t event, nlohmann::json& value) {
    using Event = nlohmann::json::parse_event_t;
    if (event == Event::object_start || event == Event::array_start) {
      open.push_back({nameOfNext(), event == Event::array_start, {}, 0});
    } else if (event == Event::object_end || event == Event::array_end) {
      open.pop_back();
    } else if (event == Event::key) {
      pendingKey = value.get<std::string>();
      if (!open.back().keys.insert(pendingKey).second) {
        std::string where;
        for (const Open& o : open) where += o.name;
        throw SceneError(path + ": " + where + (open.size() > 1 ? "." : "") + excerpt(pendingKey) +
                         ": the key is given twice in one object");
      }
    } else if (event == Event::value) {
      nameOfNext();  // counts an array's element
    }
    return true;
  };
  try {
    return nlohmann::json::parse(text, checkKeys);
  } catch (const nlohmann::json::parse_error& e) {
    // what() is "[json.exception.parse_error.101] parse error at line 3, column 10: ...".
    const std::string what = e.what();
    const size_t start = what.rfind("] ", what.find("parse error"));
    throw SceneError(path + ": invalid JSON: " + printable(start == std::string::npos ? what : what.substr(start + 2)));
  } catch (const nlohmann::json::out_of_range& e) {
    // A number beyond double's range ("1e400") is out_of_range.406, which names the number but not
    // where it is: the first such number in the text.
    const std::string what = e.what();
    const size_t quote = what.find('\'');
    const size_t end = quote == std::string::npos ? quote : what.find('\'', quote + 1);
    const std::string number = end == std::string::npos ? "" : what.substr(quote + 1, end - quote - 1);
    const size_t at = number.empty() ? std::string::npos : text.find(number);
    throw SceneError(path + ": invalid JSON: the number " + excerpt(number) + " is beyond a double's range" +
                     (at == std::string::npos ? "" : " (at " + positionOf(text, at) + ")"));
  }
}

// Each option's value as text: numbers as written, flags as true or false, strings as they are.
void loadRenderBlock(JsonFields fields, const nlohmann::json& block, RenderBlock& render) {
  render.present = true;
  if (fields.has("method")) render.method = fields.string("method");
  for (const auto& [key, value] : block.items()) {
    if (key == "method") continue;
    fields.raw(key);  // read: no unknown key here, the method's declaration judges the names
    if (value.is_boolean()) render.options.emplace_back(key, value.get<bool>() ? "true" : "false");
    else if (value.is_number()) render.options.emplace_back(key, value.dump());
    else if (value.is_string()) render.options.emplace_back(key, value.get<std::string>());
    else fields.failKey(key, "expected a number, true or false, or a string");
  }
  fields.finish();
}

}  // namespace

namespace {

// A glTF material's textures other than its base colour, emissive and normal textures: where the
// import keeps it, where the material indexes it, what messages call it, and whether it is colour
// (sRGB) or data (linear). In the order they are added to the scene.
struct GltfTexture {
  detail::TextureFile detail::MaterialSpec::*file;
  int32_t Material::*index;
  const char* role;
  bool colour;
};
const GltfTexture kGltfTextures[] = {
    {&detail::MaterialSpec::metallicRoughness, &Material::metallicRoughnessTexture, "metallic-roughness texture", false},
    {&detail::MaterialSpec::specularTexture, &Material::specularTexture, "specular texture", false},
    {&detail::MaterialSpec::sheenColourTexture, &Material::sheenColourTexture, "sheen colour texture", true},
    {&detail::MaterialSpec::sheenRoughnessTexture, &Material::sheenRoughnessTexture, "sheen roughness texture", false},
    {&detail::MaterialSpec::clearcoatTexture, &Material::clearcoatTexture, "clearcoat texture", false},
    {&detail::MaterialSpec::clearcoatRoughnessTexture, &Material::clearcoatRoughnessTexture,
     "clearcoat roughness texture", false},
    {&detail::MaterialSpec::clearcoatNormalTexture, &Material::clearcoatNormalTexture, "clearcoat normal texture",
     false},
    {&detail::MaterialSpec::transmissionTexture, &Material::transmissionTexture, "transmission texture", false},
    {&detail::MaterialSpec::specularColourTexture, &Material::specularColorTexture, "specular colour texture", true},
};

// The scene's materials from their specs (and textures), its emitters checked, then finalized:
// what every scene shares once its triangles are in.
void finishScene(Scene& scene, const detail::ObjImport& import, const std::string& path, const LoadOptions& options) {
  scene.inputFiles.insert(scene.inputFiles.end(), import.libraries.begin(), import.libraries.end());
  // An image as a texture of 8-bit texels: sRGB for colour, linear for data.
  const auto addTexture = [&](const detail::TextureFile& file, const std::string& name, const std::string& role,
                              bool colour) {
    const bool embedded = !file.bytes.empty();
    if (!embedded) scene.inputFiles.push_back(file.path);
    Texture tex;
    tex.offset = static_cast<uint32_t>(scene.texels.size());
    tex.wrapU = file.wrapU;
    tex.wrapV = file.wrapV;
    tex.nearest = file.nearest ? 1 : 0;
    tex.set = file.set;
    tex.transformed = file.transformed ? 1 : 0;
    std::copy(file.transform.begin(), file.transform.end(), tex.transform);
    const std::function<Image(ImageMetadata*)> read =
        embedded ? std::function<Image(ImageMetadata*)>([&](ImageMetadata* metadata) {
          return readImageFromMemory(file.path, fs::path(file.path).extension().string(), file.bytes, metadata);
        })
                 : std::function<Image(ImageMetadata*)>();
    const std::string context = file.origin + ": material '" + name + "' " + role;
    // glTF's colour textures (the images a glTF file holds, in memory here) are sRGB whatever a
    // PNG's gAMA, iCCP or sRGB chunk says (glTF 2.0, "Metallic-Roughness Material"); an MTL's
    // texture file is read as its metadata says.
    const auto texels = colour ? readSrgb8Texels(file.path, context, tex.width, tex.height, read, embedded)
                               : readUnorm8Texels(file.path, context, tex.width, tex.height, read);
    scene.texels.insert(scene.texels.end(), texels.begin(), texels.end());
    scene.textures.push_back(tex);
    return static_cast<int32_t>(scene.textures.size() - 1);
  };
  std::vector<std::string> steepNormalTextures;  // materials whose normal textures look like height maps
  for (const auto& spec : import.specs) {
    Material m = detail::classifyMaterial(spec);
    if (!spec.mapKd.empty())
      m.kdTexture = addTexture(spec.mapKd, spec.name, spec.mapKd.bytes.empty() ? "map_Kd" : "base colour texture", true);
    if (m.type == MaterialType::Gltf)
      for (const GltfTexture& t : kGltfTextures)
        if (!(spec.*t.file).empty()) m.*t.index = addTexture(spec.*t.file, spec.name, t.role, t.colour);
    if (!spec.emissive.empty() && !m.ke.isBlack())
      m.emissiveTexture = addTexture(spec.emissive, spec.name, "emissive texture", true);
    m.emitsBackFace = spec.doubleSided && !m.ke.isBlack() ? 1 : 0;
    m.culledBehind = spec.singleSided ? 1 : 0;
    // Normal textures perturb glTF materials' shading normals only: Lambertian hits are shaded in
    // the path tracer's lanes, from the vertex normals.
    if (m.type == MaterialType::Gltf && !spec.normal.empty()) {
      m.normalTexture = addTexture(spec.normal, spec.name, "normal texture", false);
      m.bendsNormalMap = spec.bendNormalMap ? 1 : 0;
      const Texture& t = scene.textures[size_t(m.normalTexture)];
      if (steepNormalShare(std::span(scene.texels).subspan(t.offset, size_t(t.width) * t.height)) > 0.5)
        steepNormalTextures.push_back(spec.name);
    }
    else if (!spec.normal.empty())
      scene.ignored.push_back(spec.origin + ": material '" + spec.name +
                              "': its normal texture (the material is overridden as " +
                              materialTypeName(m.type) + ")");
    scene.materials.push_back(m);
    scene.materialNames.push_back(spec.name);
  }
  if (!scene.tangents.empty()) scene.tangents.resize(scene.positions.size());  // meshes read after a glTF file's
  if (!scene.texcoords1.empty()) scene.texcoords1.resize(scene.positions.size());
  if (!scene.colours.empty()) scene.colours.resize(scene.positions.size());
  // Light selection weighs lights by power; an emitter whose power overflows a float would break it.
  for (uint32_t t = 0; t < scene.triangleCount(); ++t) {
    const uint32_t id = scene.materialIds[t];
    const Rgb ke = scene.materials[id].ke;
    if (ke.isBlack()) continue;
    const double area = triangleGeometry(scene.vertex(t, 0), scene.vertex(t, 1), scene.vertex(t, 2)).area;
    if (!(double(ke.luminance()) * area * kPi <= double(FLT_MAX)))
      throw SceneError(import.specs[id].origin + ": material '" + import.specs[id].name +
                       "': the emitted power of a triangle overflows (Ke or the triangle is too large)");
  }
  try {
    finalizeScene(scene);
  } catch (const std::invalid_argument& e) {
    throw SceneError(path + ": the light power overflows (a light or the scene is too large): " + e.what());
  }
  if (scene.lights.empty())
    throw SceneError(path + ": the scene has no light (no emissive material, no entry in 'lights')");
  if (scene.environment.clampedTexels > 0 && !options.quiet)
    std::cerr << "lucent: warning: " << scene.environment.source << ": clamped " << scene.environment.clampedTexels
              << " slightly negative texels (down to " << scene.environment.mostNegativeTexel << ") to 0\n";
  if (!steepNormalTextures.empty() && !options.quiet) {
    std::cerr << "lucent: warning: " << path << ": the normal textures of " << steepNormalTextures.size()
              << " material(s) tilt most of their texels more than 45 degrees from the surface (";
    for (size_t k = 0; k < std::min<size_t>(3, steepNormalTextures.size()); ++k)
      std::cerr << (k ? ", " : "") << "'" << steepNormalTextures[k] << "'";
    std::cerr << (steepNormalTextures.size() > 3 ? ", ...)" : ")")
              << ": height maps stored as normal textures? They are rendered as the file says.\n";
  }
  if (scene.droppedDegenerateTriangles > 0 && !options.quiet)
    std::cerr << "lucent: warning: " << path << ": dropped " << scene.droppedDegenerateTriangles
              << " degenerate (zero-area) triangles\n";
}

bool isGltf(const std::string& path) {
  const std::string extension = fs::path(path).extension().string();
  return extension == ".gltf" || extension == ".glb";
}

Scene loadGltfScene(const std::string& path, const LoadOptions& options) {
  const std::string problem = admitInputFile(path);
  if (!problem.empty()) throw SceneError(path + ": glTF file " + problem);
  Scene scene;
  scene.sourcePath = path;
  detail::ObjImport import;
  detail::GltfContent content;
  detail::importGltf(path, options.gltf, scene, import, content);
  if (!content.camera) throw SceneError(path + ": the file's scene has no camera (render it from a scene file that gives one)");
  scene.camera = *content.camera;
  if (scene.triangleCount() == 0) throw SceneError(path + ": the scene has no (non-degenerate) triangles");
  finishScene(scene, import, path, options);
  return scene;
}

}  // namespace

Scene loadScene(const std::string& jsonPath, const LoadOptions& options) {
  if (isGltf(jsonPath)) return loadGltfScene(jsonPath, options);
  const std::string problem = admitInputFile(jsonPath);
  if (!problem.empty()) throw SceneError(jsonPath + ": scene file " + problem);
  std::ifstream in(jsonPath, std::ios::binary);
  if (!in) throw SceneError(jsonPath + ": cannot open scene file");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const nlohmann::json root = parseSceneJson(text, jsonPath);
  const fs::path base = fs::absolute(jsonPath).parent_path();
  if (!options.gltf.camera.empty())
    throw SceneError(jsonPath + ": a glTF camera is chosen by name for a glTF file rendered on its own; a scene "
                                "file gives its camera");
  Scene scene;
  scene.sourcePath = jsonPath;
  scene.inputFiles.push_back(jsonPath);
  JsonFields top(root, jsonPath, "");

  loadCamera(top.object("camera"), scene);

  detail::ObjImport import;
  const auto& meshes = top.raw("meshes");
  if (!meshes.is_array() || meshes.empty()) top.failKey("meshes", "expected a non-empty array");
  for (size_t i = 0; i < meshes.size(); ++i) {
    JsonFields mesh(meshes[i], jsonPath, "meshes[" + std::to_string(i) + "]");
    if (mesh.has("gltf")) {
      // Its triangles, materials and lights; the scene file gives the camera.
      const std::string gltf = resolve(base, mesh.string("gltf"));
      requireFile(mesh, "gltf", gltf);
      GltfOptions gltfOptions = options.gltf;
      if (mesh.has("masking")) {
        const std::string masking = mesh.string("masking");
        if (masking != "separable" && masking != "height-correlated")
          mesh.failKey("masking", "expected separable or height-correlated");
        gltfOptions.heightCorrelated = masking == "height-correlated";
      }
      if (mesh.has("normal_maps")) {
        const std::string normalMaps = mesh.string("normal_maps");
        if (normalMaps != "bend" && normalMaps != "as-given") mesh.failKey("normal_maps", "expected bend or as-given");
        gltfOptions.bendNormalMaps = normalMaps == "bend";
      }
      if (mesh.has("lumens_per_watt")) {
        gltfOptions.lumensPerWatt = mesh.number("lumens_per_watt");
        if (!(gltfOptions.lumensPerWatt > 0 && gltfOptions.lumensPerWatt <= 1e6))
          mesh.failKey("lumens_per_watt", "must be in (0, 1e6]");
      }
      mesh.finish();
      if (!isGltf(gltf)) mesh.failKey("gltf", "expected a .gltf or .glb file");
      scene.inputFiles.push_back(gltf);
      detail::GltfContent content;
      detail::importGltf(gltf, gltfOptions, scene, import, content);
      continue;
    }
    const std::string obj = resolve(base, mesh.string("obj"));
    requireFile(mesh, "obj", obj);
    mesh.finish();
    scene.inputFiles.push_back(obj);
    detail::importObj(obj, scene, import);
  }
  if (scene.triangleCount() == 0) top.failKey("meshes", "the scene has no (non-degenerate) triangles");

  if (top.has("materials")) {
    JsonFields materials = top.object("materials");
    for (const auto& [name, value] : root.at("materials").items()) {
      const auto it = import.materialIndex.find(name);
      if (it == import.materialIndex.end())
        materials.failKey(name, "no mesh uses a material of this name");
      applyMaterialOverride(materials.object(name), import.specs[it->second], base);
    }
    materials.finish();
  }

  if (top.has("render")) loadRenderBlock(top.object("render"), root.at("render"), scene.render);

  if (top.has("lights")) {
    const auto& lights = top.raw("lights");
    if (!lights.is_array()) top.failKey("lights", "expected an array");
    for (size_t i = 0; i < lights.size(); ++i)
      loadLight(JsonFields(lights[i], jsonPath, "lights[" + std::to_string(i) + "]"), scene, base);
  }
  top.finish();

  finishScene(scene, import, jsonPath, options);
  return scene;
}

}  // namespace lucent
