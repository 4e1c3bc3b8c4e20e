#include "gltf_import.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>

#include "lucent/core/files.h"
#include "lucent/core/memory.h"
#include "lucent/scene/loader.h"
#include "lucent/scene/surface.h"

namespace lucent::detail {
namespace fs = std::filesystem;

namespace {

// The most elements an accessor may have, and the deepest node hierarchy followed.
constexpr size_t kMaxAccessorElements = size_t(1) << 28;
constexpr int kMaxNodeDepth = 1024;
// What a vertex and a triangle take in the scene and its Embree geometry, at most (positions,
// normals, texture coordinates and tangents; indices, material ids, Embree's build).
constexpr uint64_t kSceneBytesPerVertex = 96, kSceneBytesPerTriangle = 96;
// A memory check reads /proc (about 8 us): one is made for an accessor of this many bytes or more,
// and for a mesh instance once the scene has grown by this much since the last; a file of many small
// instances may pass the limit by at most this much before it is refused.
constexpr uint64_t kMemoryCheckBytes = uint64_t(1) << 24;

// Extensions read, and those whose content is listed as left out rather than rendered.
const std::set<std::string> kSupportedExtensions = {"KHR_lights_punctual", "KHR_materials_emissive_strength",
                                                    "KHR_texture_transform", "KHR_materials_specular",
                                                    "KHR_materials_ior", "KHR_materials_sheen",
                                                    "KHR_materials_clearcoat", "KHR_materials_transmission",
                                                    "KHR_materials_volume",
                                                    "EXT_mesh_gpu_instancing"};

struct Context {
  const tinygltf::Model& model;
  const std::string& file;
  const std::string& warnings;  // TinyGLTF's: why an image named by its URI could not be read
  [[noreturn]] void fail(const std::string& path, const std::string& what) const {
    throw SceneError(file + ": " + path + ": " + what);
  }
};

std::string at(const std::string& array, size_t index) { return array + "[" + std::to_string(index) + "]"; }

// A number of the file's as a message quotes it: 2, 0.5, 1e+300 (a cast to an integer would print
// 1e300 as -9223372036854775808).
std::string quoted(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.15g", value);
  return text;
}

// Why image `index`'s URI could not be read, as TinyGLTF's warnings say it in the line before their
// note of the image ("File not found : NAME": no such file in the glTF file's folder; a file read
// error: the loader's reason), as ": REASON"; empty if they do not say.
std::string imageReadProblem(const Context& c, size_t index) {
  const size_t note = c.warnings.find("Failed to load external 'uri' for image[" + std::to_string(index) + "]");
  if (note == std::string::npos) return "";
  std::string before = c.warnings.substr(0, note);
  while (!before.empty() && (before.back() == '\n' || before.back() == ' ')) before.pop_back();
  std::string line = before.substr(before.rfind('\n') == std::string::npos ? 0 : before.rfind('\n') + 1);
  const std::string notFound = "File not found : ";
  if (line.rfind(notFound, 0) == 0) {
    // TinyGLTF's file test is regularFileExists: the name may be there as something else.
    const fs::path folder = fs::path(c.file).parent_path(), named = folder / line.substr(notFound.size());
    const std::string problem = regularFileProblem(named);
    if (!problem.empty() && problem != "not found") return ": " + named.string() + " " + problem;
    return ": no such file in " + (folder.empty() ? std::string(".") : folder.string());
  }
  const std::string readError = "File read error : ";
  if (line.rfind(readError, 0) == 0) line.erase(0, readError.size());
  return line.empty() ? "" : ": " + line;
}

// Whether a transformed point or direction is finite as floats, as the scene keeps it.
bool finiteFloats(const std::array<double, 3>& v) {
  return std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(float(x)); });
}

// Column-major, as glTF writes matrices, in double.
struct Matrix4 {
  double m[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  Matrix4 operator*(const Matrix4& b) const {
    Matrix4 r;
    for (int col = 0; col < 4; ++col)
      for (int row = 0; row < 4; ++row) {
        double s = 0;
        for (int k = 0; k < 4; ++k) s += m[k * 4 + row] * b.m[col * 4 + k];
        r.m[col * 4 + row] = s;
      }
    return r;
  }
  std::array<double, 3> point(const double p[3]) const {
    return {m[0] * p[0] + m[4] * p[1] + m[8] * p[2] + m[12], m[1] * p[0] + m[5] * p[1] + m[9] * p[2] + m[13],
            m[2] * p[0] + m[6] * p[1] + m[10] * p[2] + m[14]};
  }
  std::array<double, 3> direction(const double d[3]) const {
    return {m[0] * d[0] + m[4] * d[1] + m[8] * d[2], m[1] * d[0] + m[5] * d[1] + m[9] * d[2],
            m[2] * d[0] + m[6] * d[1] + m[10] * d[2]};
  }
  double determinant3() const {
    return m[0] * (m[5] * m[10] - m[9] * m[6]) - m[4] * (m[1] * m[10] - m[9] * m[2]) + m[8] * (m[1] * m[6] - m[5] * m[2]);
  }
  // The cofactor matrix of the upper 3 x 3, row by row: normals transform by it (the inverse
  // transpose times the determinant, whose size normalization removes and whose sign a mirroring
  // transform's normals are turned back by).
  std::array<double, 9> normalMatrix() const {
    const double a = m[0], b = m[4], c = m[8], d = m[1], e = m[5], f = m[9], g = m[2], h = m[6], i = m[10];
    return {e * i - f * h, f * g - d * i, d * h - e * g, c * h - b * i, a * i - c * g,
            b * g - a * h, b * f - c * e, c * d - a * f, a * e - b * d};
  }
};

// T * R * S for translation t, the rotation of unit quaternion q (x, y, z, w) and scale s, column by
// column.
Matrix4 trsMatrix(const double t[3], const double q[4], const double s[3]) {
  const double x = q[0], y = q[1], z = q[2], w = q[3];
  const double rot[9] = {1 - 2 * (y * y + z * z), 2 * (x * y + z * w),     2 * (x * z - y * w),
                         2 * (x * y - z * w),     1 - 2 * (x * x + z * z), 2 * (y * z + x * w),
                         2 * (x * z + y * w),     2 * (y * z - x * w),     1 - 2 * (x * x + y * y)};
  Matrix4 r;
  for (int col = 0; col < 3; ++col)
    for (int row = 0; row < 3; ++row) r.m[col * 4 + row] = rot[col * 3 + row] * s[col];
  for (int k = 0; k < 3; ++k) r.m[12 + k] = t[k];
  return r;
}

// Quaternion q made unit length in place; false for a zero (or non-finite) one.
bool normalizeQuaternion(double q[4]) {
  const double len = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  if (!(len > 0) || !std::isfinite(len)) return false;
  for (int k = 0; k < 4; ++k) q[k] /= len;
  return true;
}

Matrix4 nodeMatrix(const Context& c, const tinygltf::Node& node, const std::string& path) {
  const auto finite = [&](const std::vector<double>& v, const char* key) {
    for (const double x : v)
      if (!std::isfinite(x)) c.fail(path + "." + key, "has a non-finite value");
  };
  if (!node.matrix.empty()) {
    if (node.matrix.size() != 16) c.fail(path + ".matrix", "expected 16 numbers");
    finite(node.matrix, "matrix");
    Matrix4 r;
    std::copy(node.matrix.begin(), node.matrix.end(), r.m);
    return r;
  }
  if (!node.translation.empty() && node.translation.size() != 3) c.fail(path + ".translation", "expected 3 numbers");
  if (!node.rotation.empty() && node.rotation.size() != 4) c.fail(path + ".rotation", "expected 4 numbers");
  if (!node.scale.empty() && node.scale.size() != 3) c.fail(path + ".scale", "expected 3 numbers");
  finite(node.translation, "translation");
  finite(node.rotation, "rotation");
  finite(node.scale, "scale");
  double q[4] = {0, 0, 0, 1}, t[3] = {0, 0, 0}, s[3] = {1, 1, 1};
  if (!node.rotation.empty()) {
    std::copy(node.rotation.begin(), node.rotation.end(), q);
    if (!normalizeQuaternion(q)) c.fail(path + ".rotation", "is not a rotation (a zero quaternion)");
  }
  if (!node.translation.empty()) std::copy(node.translation.begin(), node.translation.end(), t);
  if (!node.scale.empty()) std::copy(node.scale.begin(), node.scale.end(), s);
  return trsMatrix(t, q, s);
}

int componentBytes(int type) {
  switch (type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
    default: return 0;
  }
}

const char* typeName(int type) {
  switch (type) {
    case TINYGLTF_TYPE_SCALAR: return "SCALAR";
    case TINYGLTF_TYPE_VEC2: return "VEC2";
    case TINYGLTF_TYPE_VEC3: return "VEC3";
    case TINYGLTF_TYPE_VEC4: return "VEC4";
    default: return "a matrix";
  }
}

// One component as glTF defines it, normalized integers mapped to [0, 1] or [-1, 1].
double component(const unsigned char* p, int type, bool normalized) {
  switch (type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE: {
      int8_t v;
      std::memcpy(&v, p, 1);
      return normalized ? std::max(v / 127.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return normalized ? p[0] / 255.0 : p[0];
    case TINYGLTF_COMPONENT_TYPE_SHORT: {
      int16_t v;
      std::memcpy(&v, p, 2);
      return normalized ? std::max(v / 32767.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
      uint16_t v;
      std::memcpy(&v, p, 2);
      return normalized ? v / 65535.0 : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
      uint32_t v;
      std::memcpy(&v, p, 4);
      return v;
    }
    default: {
      float v;
      std::memcpy(&v, p, 4);
      return v;
    }
  }
}

// The bytes of buffer view `index` that hold `count` elements of `elementBytes` from `offset`, `stride`
// apart (0: packed): checked against the view and the view against its buffer.
const unsigned char* viewBytes(const Context& c, int index, const std::string& user, size_t offset, size_t count,
                               size_t elementBytes, size_t* stride) {
  const auto& views = c.model.bufferViews;
  if (index < 0 || size_t(index) >= views.size()) c.fail(user, "buffer view " + std::to_string(index) + " does not exist");
  const tinygltf::BufferView& view = views[size_t(index)];
  const std::string path = at("bufferViews", size_t(index));
  if (view.buffer < 0 || size_t(view.buffer) >= c.model.buffers.size())
    c.fail(path + ".buffer", "buffer " + std::to_string(view.buffer) + " does not exist");
  const auto& data = c.model.buffers[size_t(view.buffer)].data;
  if (view.byteOffset > data.size() || view.byteLength > data.size() - view.byteOffset)
    c.fail(path, "bytes [" + std::to_string(view.byteOffset) + ", " + std::to_string(view.byteOffset) + " + " +
                     std::to_string(view.byteLength) + ") lie beyond its buffer's " + std::to_string(data.size()));
  const size_t step = view.byteStride == 0 ? elementBytes : view.byteStride;
  if (view.byteStride != 0 && (view.byteStride < elementBytes || view.byteStride > 252))
    c.fail(path + ".byteStride", std::to_string(view.byteStride) + " is not in [" + std::to_string(elementBytes) +
                                     ", 252] for elements of " + std::to_string(elementBytes) + " bytes");
  // count <= 2^28 and step <= 252: no overflow in 64 bits.
  if (offset > view.byteLength || (count - 1) * step + elementBytes > view.byteLength - offset)
    c.fail(user, std::to_string(count) + " elements of " + std::to_string(elementBytes) + " bytes from byte " +
                     std::to_string(offset) + " do not fit " + path + " (" + std::to_string(view.byteLength) +
                     " bytes)");
  *stride = step;
  return data.data() + view.byteOffset + offset;
}

// The elements of accessor `index` (named at `user`), `components` doubles each, of the type
// expected and one of the component types allowed; sparse substitutions applied.
std::vector<double> readAccessor(const Context& c, int index, const std::string& user, int expectedType,
                                 std::initializer_list<int> componentTypes) {
  const auto& accessors = c.model.accessors;
  if (index < 0 || size_t(index) >= accessors.size()) c.fail(user, "accessor " + std::to_string(index) + " does not exist");
  const tinygltf::Accessor& a = accessors[size_t(index)];
  const std::string path = at("accessors", size_t(index));
  if (a.type != expectedType) c.fail(path, std::string("is ") + typeName(a.type) + ", expected " + typeName(expectedType));
  if (std::find(componentTypes.begin(), componentTypes.end(), a.componentType) == componentTypes.end())
    c.fail(path + ".componentType", std::to_string(a.componentType) + " is not allowed for " + user);
  if (a.count == 0 || a.count > kMaxAccessorElements)
    c.fail(path + ".count", std::to_string(a.count) + " is not in [1, 2^28]");
  const size_t n = size_t(tinygltf::GetNumComponentsInType(uint32_t(a.type)));
  const size_t bytes = size_t(componentBytes(a.componentType));
  // What the elements would take is bounded by what the file holds before it is allocated: the
  // elements of a buffer view lie in it; those without one (zeros, perhaps with sparse values) may be
  // no more than its buffers could hold.
  size_t stride = 0;
  const unsigned char* p = a.bufferView >= 0 ? viewBytes(c, a.bufferView, path, a.byteOffset, a.count, n * bytes, &stride)
                                             : nullptr;
  if (a.bufferView < 0) {
    uint64_t bufferBytes = 0;
    for (const tinygltf::Buffer& buffer : c.model.buffers) bufferBytes += buffer.data.size();
    if (uint64_t(a.count) * n * bytes > std::max<uint64_t>(bufferBytes, 4096))
      c.fail(path + ".count", std::to_string(a.count) + " elements of " + std::to_string(n * bytes) +
                                  " bytes without a bufferView: more than the file's buffers (" +
                                  std::to_string(bufferBytes) + " bytes) could hold");
  }
  if (uint64_t(a.count) * n * sizeof(double) >= kMemoryCheckBytes)
    requireMemory(uint64_t(a.count) * n * sizeof(double), c.file + ": " + path, "render a smaller scene, or raise --memory-limit");
  std::vector<double> out(a.count * n, 0.0);
  if (p) {
    for (size_t e = 0; e < a.count; ++e)
      for (size_t k = 0; k < n; ++k) out[e * n + k] = component(p + e * stride + k * bytes, a.componentType, a.normalized);
  }
  if (a.sparse.isSparse) {
    const std::string sparse = path + ".sparse";
    if (a.sparse.count < 1 || size_t(a.sparse.count) > a.count)
      c.fail(sparse + ".count", std::to_string(a.sparse.count) + " is not in [1, " + std::to_string(a.count) + "]");
    const size_t count = size_t(a.sparse.count);
    const int indexType = a.sparse.indices.componentType;
    if (indexType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && indexType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
        indexType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
      c.fail(sparse + ".indices.componentType", "must be an unsigned integer type");
    size_t indexStride = 0, valueStride = 0;
    const unsigned char* indices = viewBytes(c, a.sparse.indices.bufferView, sparse + ".indices",
                                             size_t(std::max(a.sparse.indices.byteOffset, 0)), count,
                                             size_t(componentBytes(indexType)), &indexStride);
    const unsigned char* values = viewBytes(c, a.sparse.values.bufferView, sparse + ".values",
                                            size_t(std::max(a.sparse.values.byteOffset, 0)), count, n * bytes, &valueStride);
    double previous = -1;
    for (size_t s = 0; s < count; ++s) {
      const double target = component(indices + s * indexStride, indexType, false);
      if (target <= previous || target >= double(a.count))
        c.fail(sparse + ".indices", "element " + std::to_string(s) + " (" + std::to_string(size_t(target)) +
                                        ") is not increasing and below the count " + std::to_string(a.count));
      previous = target;
      for (size_t k = 0; k < n; ++k)
        out[size_t(target) * n + k] = component(values + s * valueStride + k * bytes, a.componentType, a.normalized);
    }
  }
  for (size_t i = 0; i < out.size(); ++i)
    if (!std::isfinite(out[i])) c.fail(path, "element " + std::to_string(i / n) + " is not finite");
  return out;
}

double number(const tinygltf::Value& object, const char* key, double fallback) {
  if (!object.IsObject() || !object.Has(key)) return fallback;
  const tinygltf::Value& v = object.Get(key);
  return v.IsNumber() ? v.GetNumberAsDouble() : v.IsInt() ? double(v.GetNumberAsInt()) : fallback;
}

const tinygltf::Value* extension(const tinygltf::ExtensionMap& extensions, const char* name) {
  const auto it = extensions.find(name);
  return it == extensions.end() ? nullptr : &it->second;
}

// A texture's KHR_texture_transform, as the 2 x 3 matrix T R S of glTF's texture coordinates
// (origin at the image's top left): u' = m[0] u + m[1] v + m[2], v' = m[3] u + m[4] v + m[5].
using UvTransform = std::array<double, 6>;
constexpr UvTransform kIdentityUv = {1, 0, 0, 0, 1, 0};

// The texture coordinates a texture reads: the set (TEXCOORD_0 or _1) and its transform.
struct TextureCoordinates {
  int set = 0;
  UvTransform transform = kIdentityUv;
};

int coordinateSet(const Context& c, double set, const std::string& path) {
  if (set != 0 && set != 1) c.fail(path, "TEXCOORD_" + quoted(set) + " is not read (TEXCOORD_0 and _1 are)");
  return int(set);
}

UvTransform textureTransform(const Context& c, const tinygltf::Value& e, const std::string& path, int& set) {
  const auto pair = [&](const char* key, double fallback) -> std::array<double, 2> {
    if (!e.Has(key)) return {fallback, fallback};
    const tinygltf::Value& v = e.Get(key);
    if (!v.IsArray() || v.ArrayLen() != 2 || !v.Get(0).IsNumber() || !v.Get(1).IsNumber())
      c.fail(path + "." + key, "expected 2 numbers");
    return {v.Get(0).GetNumberAsDouble(), v.Get(1).GetNumberAsDouble()};
  };
  const std::array<double, 2> offset = pair("offset", 0), scale = pair("scale", 1);
  const double rotation = number(e, "rotation", 0);
  if (e.Has("texCoord")) set = coordinateSet(c, number(e, "texCoord", 0), path + ".texCoord");
  for (const double x : {offset[0], offset[1], scale[0], scale[1], rotation})
    if (!std::isfinite(x) || std::abs(x) > kMaxInputMagnitude) c.fail(path, "its values must be finite and at most 1e15");
  const double cs = std::cos(rotation), sn = std::sin(rotation);
  // T * R * S with R = [[cos, sin], [-sin, cos]], the extension's rotation.
  return {cs * scale[0], sn * scale[1], offset[0], -sn * scale[0], cs * scale[1], offset[1]};
}

// A texture's image: its bytes (a buffer view, checked, or what TinyGLTF read from a URI) for the
// loader to decode; `what` names the texture's role in messages and in the ignored list.
TextureFile textureImage(const Context& c, const tinygltf::TextureInfo& info, const std::string& path) {
  TextureCoordinates coordinates;
  coordinates.set = coordinateSet(c, info.texCoord, path + ".texCoord");
  if (const tinygltf::Value* e = extension(info.extensions, "KHR_texture_transform"))
    coordinates.transform = textureTransform(c, *e, path + ".extensions.KHR_texture_transform", coordinates.set);
  if (info.index < 0 || size_t(info.index) >= c.model.textures.size())
    c.fail(path + ".index", "texture " + std::to_string(info.index) + " does not exist");
  const tinygltf::Texture& texture = c.model.textures[size_t(info.index)];
  const std::string texturePath = at("textures", size_t(info.index));
  TextureFile file;
  // The transform in Lucent's coordinates, whose v is glTF's 1 - v: u' = m0 u - m1 v + (m1 + m2),
  // v' = -m3 u + m4 v + (1 - m4 - m5).
  const UvTransform& m = coordinates.transform;
  file.set = uint32_t(coordinates.set);
  file.transformed = m != kIdentityUv;
  file.transform = {float(m[0]), float(-m[1]), float(m[1] + m[2]), float(-m[3]), float(m[4]), float(1 - m[4] - m[5])};
  if (texture.sampler >= 0) {
    if (size_t(texture.sampler) >= c.model.samplers.size())
      c.fail(texturePath + ".sampler", "sampler " + std::to_string(texture.sampler) + " does not exist");
    const tinygltf::Sampler& sampler = c.model.samplers[size_t(texture.sampler)];
    const std::string samplerPath = at("samplers", size_t(texture.sampler));
    const auto wrap = [&](int mode, const char* key) {
      switch (mode) {
        case TINYGLTF_TEXTURE_WRAP_REPEAT: return TextureWrap::Repeat;
        case TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE: return TextureWrap::Clamp;
        case TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT: return TextureWrap::Mirror;
        default: c.fail(samplerPath + "." + key, std::to_string(mode) + " is not a glTF wrapping mode");
      }
    };
    file.wrapU = wrap(sampler.wrapS, "wrapS");
    file.wrapV = wrap(sampler.wrapT, "wrapT");
    file.nearest = sampler.magFilter == TINYGLTF_TEXTURE_FILTER_NEAREST;
  }
  if (texture.source < 0 || size_t(texture.source) >= c.model.images.size())
    c.fail(texturePath + ".source", "image " + std::to_string(texture.source) + " does not exist");
  const tinygltf::Image& image = c.model.images[size_t(texture.source)];
  const std::string imagePath = at("images", size_t(texture.source));
  if (image.bufferView >= 0) {
    const auto& views = c.model.bufferViews;
    const size_t length = size_t(image.bufferView) < views.size() ? views[size_t(image.bufferView)].byteLength : 0;
    if (length == 0) c.fail(imagePath + ".bufferView", "is missing or empty");
    size_t stride = 0;
    const unsigned char* p = viewBytes(c, image.bufferView, imagePath, 0, 1, length, &stride);
    file.bytes.assign(p, p + length);
  } else {
    file.bytes = image.image;  // as read from its URI (keepImageBytes)
    if (file.bytes.empty())
      c.fail(imagePath + ".uri", "'" + image.uri + "' could not be read" + imageReadProblem(c, size_t(texture.source)));
  }
  const auto& bytes = file.bytes;
  const bool png = bytes.size() >= 8 && std::memcmp(bytes.data(), "\x89PNG\r\n\x1a\n", 8) == 0;
  const bool jpeg = bytes.size() >= 3 && bytes[0] == 0xff && bytes[1] == 0xd8 && bytes[2] == 0xff;
  if (!png && !jpeg) c.fail(imagePath, "is neither a PNG nor a JPEG image");
  file.path = c.file + "#" + imagePath + (png ? ".png" : ".jpg");
  file.origin = c.file + ": " + path;
  // An image from a file of its own: named too, as the URI gives it.
  if (image.bufferView < 0 && image.uri.rfind("data:", 0) != 0) file.origin += " (" + imagePath + ": '" + image.uri + "')";
  return file;
}

// A textureInfo object inside an extension (TinyGLTF leaves those as JSON values).
tinygltf::TextureInfo textureInfo(const Context& c, const tinygltf::Value& parent, const char* key, const std::string& at) {
  const tinygltf::Value& v = parent.Get(key);
  const std::string path = at + "." + key;
  if (!v.IsObject()) c.fail(path, "expected a textureInfo object");
  tinygltf::TextureInfo info;
  const auto integer = [&](const char* field, int fallback) {
    if (!v.Has(field)) return fallback;
    if (!v.Get(field).IsNumber() && !v.Get(field).IsInt()) c.fail(path + "." + field, "expected an index");
    const double x = number(v, field, fallback);
    if (!(x >= 0 && x <= 2147483647.0) || x != std::floor(x)) c.fail(path + "." + field, "expected an index");
    return int(x);
  };
  if (!v.Has("index")) c.fail(path + ".index", "is required");
  info.index = integer("index", -1);
  info.texCoord = integer("texCoord", 0);
  if (v.Has("extensions") && v.Get("extensions").IsObject()) {
    const tinygltf::Value& extensions = v.Get("extensions");
    for (const std::string& name : extensions.Keys()) info.extensions[name] = extensions.Get(name);
  }
  return info;
}

double unitNumber(const Context& c, double value, const std::string& path) {
  if (!(value >= 0 && value <= 1)) c.fail(path, "must be in [0, 1]");
  return value;
}

// An extension's colour factor at `path`: 3 numbers, each in [0, most] (`range` writes it).
Rgb rgbFactor(const Context& c, const tinygltf::Value& colour, const std::string& path, double most, const char* range) {
  if (!colour.IsArray() || colour.ArrayLen() != 3) c.fail(path, "expected 3 numbers");
  Rgb out;
  for (int k = 0; k < 3; ++k) {
    const tinygltf::Value& v = colour.Get(k);
    const double x = v.IsNumber() ? v.GetNumberAsDouble() : v.IsInt() ? double(v.GetNumberAsInt()) : -1;
    if (!(x >= 0 && x <= most)) c.fail(path, std::string("every value must be in ") + range);
    out[k] = float(x);
  }
  return out;
}

// The specification's default material, for primitives that name none: a white rough metal.
MaterialSpec defaultMaterial(const Context& c, GgxMasking masking) {
  MaterialSpec spec;
  spec.name = "glTF default material";
  spec.origin = c.file + ": the default material";
  spec.type = MaterialType::Gltf;
  spec.masking = masking;
  spec.kd = Rgb(1.0f);
  spec.ks = Rgb(1.0f);
  spec.ni = 1.5f;
  spec.metallic = 1.0f;
  spec.singleSided = true;  // the default material's doubleSided is false
  return spec;
}

// The extensions that layer on or replace part of Appendix B's BRDF (bsdf/gltf_metal_rough.h):
// KHR_materials_sheen, _clearcoat, _transmission and _volume.
void readLayerExtensions(const Context& c, const tinygltf::Material& m, const std::string& path,
                         const std::string& named, MaterialSpec& spec, std::vector<std::string>& ignored) {
  // KHR_materials_sheen: a sheen layer over the base (bsdf/sheen.h).
  if (const tinygltf::Value* e = extension(m.extensions, "KHR_materials_sheen")) {
    const std::string at = path + ".extensions.KHR_materials_sheen";
    if (e->Has("sheenColorFactor")) spec.sheenColour = rgbFactor(c, e->Get("sheenColorFactor"), at + ".sheenColorFactor", 1, "[0, 1]");
    spec.sheenRoughness = float(unitNumber(c, number(*e, "sheenRoughnessFactor", 0), at + ".sheenRoughnessFactor"));
    if (e->Has("sheenColorTexture"))
      spec.sheenColourTexture = textureImage(c, textureInfo(c, *e, "sheenColorTexture", at), at + ".sheenColorTexture");
    if (e->Has("sheenRoughnessTexture"))
      spec.sheenRoughnessTexture =
          textureImage(c, textureInfo(c, *e, "sheenRoughnessTexture", at), at + ".sheenRoughnessTexture");
  }
  // KHR_materials_clearcoat: a clear coat over both (bsdf/gltf_metal_rough.h).
  if (const tinygltf::Value* e = extension(m.extensions, "KHR_materials_clearcoat")) {
    const std::string at = path + ".extensions.KHR_materials_clearcoat";
    spec.clearcoat = float(unitNumber(c, number(*e, "clearcoatFactor", 0), at + ".clearcoatFactor"));
    spec.clearcoatRoughness = float(unitNumber(c, number(*e, "clearcoatRoughnessFactor", 0), at + ".clearcoatRoughnessFactor"));
    if (spec.clearcoat > 0 && spec.clearcoatRoughness * spec.clearcoatRoughness < kMinGgxAlpha) {
      const std::string smallest = std::to_string(std::sqrt(kMinGgxAlpha)).substr(0, 6);
      ignored.push_back(named + ": clearcoat roughness below " + smallest + " (rendered as " + smallest + ")");
    }
    if (e->Has("clearcoatTexture"))
      spec.clearcoatTexture = textureImage(c, textureInfo(c, *e, "clearcoatTexture", at), at + ".clearcoatTexture");
    if (e->Has("clearcoatRoughnessTexture"))
      spec.clearcoatRoughnessTexture =
          textureImage(c, textureInfo(c, *e, "clearcoatRoughnessTexture", at), at + ".clearcoatRoughnessTexture");
    if (e->Has("clearcoatNormalTexture")) {
      const std::string normalAt = at + ".clearcoatNormalTexture";
      spec.clearcoatNormalTexture = textureImage(c, textureInfo(c, *e, "clearcoatNormalTexture", at), normalAt);
      const double scale = number(e->Get("clearcoatNormalTexture"), "scale", 1);
      if (!(std::abs(scale) <= kMaxInputMagnitude)) c.fail(normalAt + ".scale", "must be finite and at most 1e15");
      spec.clearcoatNormalScale = float(scale);
    }
  }
  // KHR_materials_transmission: thin-walled, the diffuse base's share that passes through.
  if (const tinygltf::Value* e = extension(m.extensions, "KHR_materials_transmission")) {
    const std::string at = path + ".extensions.KHR_materials_transmission";
    spec.transmission = float(unitNumber(c, number(*e, "transmissionFactor", 0), at + ".transmissionFactor"));
    if (e->Has("transmissionTexture"))
      spec.transmissionTexture = textureImage(c, textureInfo(c, *e, "transmissionTexture", at), at + ".transmissionTexture");
  }
  // KHR_materials_volume: a thickness above 0 makes the surface a medium's boundary (light enters
  // where it transmits). Its thicknessTexture is a rasterizer's estimate of the path length inside,
  // which a ray tracer measures (the extension: "ray-tracers should ignore the thickness texture").
  if (const tinygltf::Value* e = extension(m.extensions, "KHR_materials_volume")) {
    const std::string at = path + ".extensions.KHR_materials_volume";
    const double thickness = number(*e, "thicknessFactor", 0);
    if (!(thickness >= 0 && thickness <= kMaxInputMagnitude)) c.fail(at + ".thicknessFactor", "must be in [0, 1e15]");
    if (e->Has("thicknessTexture")) textureInfo(c, *e, "thicknessTexture", at);
    const double distance = number(*e, "attenuationDistance", kInf);
    if (!(float(distance) > 0)) c.fail(at + ".attenuationDistance", "must be above 0 (as a float)");
    if (e->Has("attenuationColor")) spec.attenuationColour = rgbFactor(c, e->Get("attenuationColor"), at + ".attenuationColor", 1, "[0, 1]");
    spec.attenuationDistance = float(distance);
    spec.boundsVolume = thickness > 0 && spec.transmission > 0;
  }
}

// A glTF material: pbrMetallicRoughness with KHR_materials_ior and KHR_materials_specular as
// Appendix B's BRDF (the masking term's form as `masking` says), and its emission; what that leaves
// out is listed in `ignored`, and what would change the image beyond that is refused.
MaterialSpec materialSpec(const Context& c, size_t index, GgxMasking masking, std::vector<std::string>& ignored) {
  const tinygltf::Material& m = c.model.materials[index];
  const std::string path = at("materials", index);
  const std::string named = c.file + ": " + path + (m.name.empty() ? "" : " '" + m.name + "'");
  const auto& pbr = m.pbrMetallicRoughness;
  const std::string pbrPath = path + ".pbrMetallicRoughness";
  if (m.occlusionTexture.index >= 0)
    ignored.push_back(named + ": occlusionTexture (a rasterizer's stand-in for the occlusion light transport computes)");
  if (pbr.baseColorFactor.size() != 4) c.fail(pbrPath + ".baseColorFactor", "expected 4 numbers");
  for (const double v : pbr.baseColorFactor)
    if (!(v >= 0 && v <= 1)) c.fail(pbrPath + ".baseColorFactor", "every value must be in [0, 1]");
  MaterialSpec spec;
  spec.name = m.name.empty() ? path : m.name;
  spec.origin = c.file + ": " + path;
  spec.type = MaterialType::Gltf;
  spec.masking = masking;
  spec.kd = Rgb(float(pbr.baseColorFactor[0]), float(pbr.baseColorFactor[1]), float(pbr.baseColorFactor[2]));
  spec.metallic = float(unitNumber(c, pbr.metallicFactor, pbrPath + ".metallicFactor"));
  spec.roughness = float(unitNumber(c, pbr.roughnessFactor, pbrPath + ".roughnessFactor"));
  if (spec.roughness * spec.roughness < kMinGgxAlpha) {
    const std::string smallest = std::to_string(std::sqrt(kMinGgxAlpha)).substr(0, 6);
    ignored.push_back(named + ": roughness below " + smallest + " (rendered as " + smallest + ")");
  }
  if (pbr.baseColorTexture.index >= 0) spec.mapKd = textureImage(c, pbr.baseColorTexture, pbrPath + ".baseColorTexture");
  if (pbr.metallicRoughnessTexture.index >= 0)
    spec.metallicRoughness = textureImage(c, pbr.metallicRoughnessTexture, pbrPath + ".metallicRoughnessTexture");
  if (m.normalTexture.index >= 0) {
    tinygltf::TextureInfo info;
    info.index = m.normalTexture.index;
    info.texCoord = m.normalTexture.texCoord;
    info.extensions = m.normalTexture.extensions;
    spec.normal = textureImage(c, info, path + ".normalTexture");
    if (!(std::abs(m.normalTexture.scale) <= kMaxInputMagnitude))
      c.fail(path + ".normalTexture.scale", "must be finite and at most 1e15");
    spec.normalScale = float(m.normalTexture.scale);
  }
  if (m.emissiveTexture.index >= 0)
    spec.emissive = textureImage(c, m.emissiveTexture, path + ".emissiveTexture");
  spec.doubleSided = m.doubleSided;
  spec.singleSided = !m.doubleSided;
  double strength = 1;
  if (const tinygltf::Value* e = extension(m.extensions, "KHR_materials_emissive_strength"))
    strength = number(*e, "emissiveStrength", 1);
  if (m.emissiveFactor.size() != 3) c.fail(path + ".emissiveFactor", "expected 3 numbers");
  for (int k = 0; k < 3; ++k) {
    const double e = m.emissiveFactor[size_t(k)] * strength;
    if (!(e >= 0) || !std::isfinite(e) || e > 1e15)
      c.fail(path + ".emissiveFactor", "times the emissive strength must be finite, non-negative and at most 1e15");
    spec.ke[k] = float(e);
  }
  // Alpha: the base colour factor's times the base colour texture's A, against the cutoff (MASK),
  // or as stochastic transparency (BLEND).
  spec.baseAlpha = float(pbr.baseColorFactor[3]);
  if (m.alphaMode == "MASK") {
    spec.alphaMode = AlphaMode::Mask;
    if (!(m.alphaCutoff >= 0 && m.alphaCutoff <= kMaxInputMagnitude)) c.fail(path + ".alphaCutoff", "must be 0 or more");
    spec.alphaCutoff = float(m.alphaCutoff);
  } else if (m.alphaMode == "BLEND") {
    spec.alphaMode = AlphaMode::Blend;
  } else if (m.alphaMode != "OPAQUE") {
    c.fail(path + ".alphaMode", "'" + m.alphaMode + "' is not OPAQUE, MASK or BLEND");
  }
  // Appendix B's dielectric, its Fresnel term from KHR_materials_ior and KHR_materials_specular.
  spec.ks = Rgb(1.0f);
  if (const tinygltf::Value* e = extension(m.extensions, "KHR_materials_specular")) {
    const std::string at = path + ".extensions.KHR_materials_specular";
    spec.specular = float(unitNumber(c, number(*e, "specularFactor", 1), at + ".specularFactor"));
    if (e->Has("specularColorFactor"))
      spec.ks = rgbFactor(c, e->Get("specularColorFactor"), at + ".specularColorFactor", kMaxInputMagnitude, "[0, 1e15]");
    if (e->Has("specularTexture")) spec.specularTexture = textureImage(c, textureInfo(c, *e, "specularTexture", at), at + ".specularTexture");
    if (e->Has("specularColorTexture"))
      spec.specularColourTexture =
          textureImage(c, textureInfo(c, *e, "specularColorTexture", at), at + ".specularColorTexture");
  }
  readLayerExtensions(c, m, path, named, spec, ignored);
  spec.ni = 1.5f;
  if (const tinygltf::Value* e = extension(m.extensions, "KHR_materials_ior")) {
    const double ior = number(*e, "ior", 1.5);
    // The extension allows 0 (F0 = 1, for specular-glossiness conversions) and [1, inf).
    if (!(ior == 0 || (ior >= 1 && ior <= kMaxInputMagnitude)))
      c.fail(path + ".extensions.KHR_materials_ior.ior", "must be 0 or in [1, 1e15]");
    spec.ni = float(ior);
  }
  // An index of 0 reflects all (F0 = 1): nothing enters a volume. A volume's boundary is seen from
  // both sides whatever doubleSided says (the extension: it "has no effect on volume boundaries").
  if (spec.ni < 1) spec.boundsVolume = false;
  if (spec.boundsVolume) spec.singleSided = false;
  return spec;
}

// Imports one node's mesh, placed by `world`, and its lights; then its children.
struct NodeWalk {
  const Context& c;
  Scene& scene;
  ObjImport& import;
  GltfContent& content;
  double lumensPerWatt;
  const std::string& cameraName;           // empty: the first camera
  std::vector<std::string> cameraNames;    // the cameras passed over for another name
  GgxMasking masking;                      // every material's Smith form
  bool bendNormalMaps;                     // GltfOptions::bendNormalMaps
  std::map<int, uint32_t> materialOf;      // glTF material (-1: the default) -> spec
  uint64_t skippedPrimitives = 0;      // points and lines
  uint64_t grownSinceMemoryCheck = 0;  // bytes the scene took since the last memory check

  uint32_t material(int index, const std::string& user) {
    if (const auto it = materialOf.find(index); it != materialOf.end()) return it->second;
    if (index >= 0 && size_t(index) >= c.model.materials.size())
      c.fail(user, "material " + std::to_string(index) + " does not exist");
    MaterialSpec spec = index < 0 ? defaultMaterial(c, masking) : materialSpec(c, size_t(index), masking, scene.ignored);
    std::string name = spec.name;
    if (import.materialIndex.count(name)) name += " (" + c.file + ": " + at("materials", size_t(index)) + ")";
    spec.name = name;
    spec.bendNormalMap = bendNormalMaps;
    const uint32_t id = uint32_t(import.specs.size());
    import.materialIndex.emplace(name, id);
    import.specs.push_back(spec);
    materialOf.emplace(index, id);
    return id;
  }

  // The primitive's triangles as corners (three vertex indices each), counter-clockwise as the
  // specification orders strips and fans.
  std::vector<uint32_t> triangleCorners(const tinygltf::Primitive& p, int mode, const std::string& path, size_t vertices) {
    std::vector<uint32_t> index;
    if (p.indices >= 0) {
      const std::vector<double> read = readAccessor(c, p.indices, path + ".indices", TINYGLTF_TYPE_SCALAR,
                                                    {TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT,
                                                     TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT});
      index.reserve(read.size());
      for (size_t i = 0; i < read.size(); ++i) {
        if (read[i] >= double(vertices))
          c.fail(path + ".indices", "element " + std::to_string(i) + " (" + std::to_string(uint64_t(read[i])) +
                                        ") is not below the vertex count " + std::to_string(vertices));
        index.push_back(uint32_t(read[i]));
      }
    } else {
      for (size_t i = 0; i < vertices; ++i) index.push_back(uint32_t(i));
    }
    std::vector<uint32_t> corners;
    if (mode == TINYGLTF_MODE_TRIANGLES) {
      corners.assign(index.begin(), index.end() - ptrdiff_t(index.size() % 3));
    } else {
      for (size_t i = 0; i + 2 < index.size(); ++i) {
        if (mode == TINYGLTF_MODE_TRIANGLE_STRIP)
          corners.insert(corners.end(), {index[i], index[i + 1 + i % 2], index[i + 2 - i % 2]});
        else
          corners.insert(corners.end(), {index[i + 1], index[i + 2], index[0]});
      }
    }

    return corners;
  }

  // COLOR_0 (accessor `index`, none where negative) of a primitive's vertices: RGB or RGBA, floats or
  // normalized unsigned bytes or shorts, each in [0, 1].
  std::vector<double> readColours(int index, const std::string& user, size_t vertices) const {
    if (index < 0) return {};
    const bool rgba = size_t(index) < c.model.accessors.size() && c.model.accessors[size_t(index)].type == TINYGLTF_TYPE_VEC4;
    const std::vector<double> read =
        readAccessor(c, index, user, rgba ? TINYGLTF_TYPE_VEC4 : TINYGLTF_TYPE_VEC3,
                     {TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT});
    const tinygltf::Accessor& a = c.model.accessors[size_t(index)];
    const std::string accessorPath = at("accessors", size_t(index));
    if (a.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT && !a.normalized)
      c.fail(accessorPath + ".normalized", "must be true for " + user + " of integers");
    if (read.size() / (rgba ? 4 : 3) != vertices)
      c.fail(user, "its count differs from POSITION's " + std::to_string(vertices));
    for (size_t k = 0; k < read.size(); ++k)
      if (!(read[k] >= 0 && read[k] <= 1))
        c.fail(accessorPath, "element " + std::to_string(k / (rgba ? 4 : 3)) + " is not a colour in [0, 1]");
    return read;
  }

  void primitive(const tinygltf::Primitive& p, const std::string& path, const Matrix4& world) {
    const int mode = p.mode < 0 ? TINYGLTF_MODE_TRIANGLES : p.mode;
    if (mode == TINYGLTF_MODE_POINTS || mode == TINYGLTF_MODE_LINE || mode == TINYGLTF_MODE_LINE_LOOP ||
        mode == TINYGLTF_MODE_LINE_STRIP) {
      ++skippedPrimitives;
      return;
    }
    if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP && mode != TINYGLTF_MODE_TRIANGLE_FAN)
      c.fail(path + ".mode", std::to_string(mode) + " is not a glTF primitive mode");
    const auto attribute = [&](const char* name) {
      const auto it = p.attributes.find(name);
      return it == p.attributes.end() ? -1 : it->second;
    };
    if (attribute("POSITION") < 0) c.fail(path + ".attributes", "has no POSITION");
    const std::vector<double> positions = readAccessor(c, attribute("POSITION"), path + ".attributes.POSITION",
                                                       TINYGLTF_TYPE_VEC3, {TINYGLTF_COMPONENT_TYPE_FLOAT});
    const size_t vertices = positions.size() / 3;
    std::vector<double> normals, texcoords;
    if (attribute("NORMAL") >= 0)
      normals = readAccessor(c, attribute("NORMAL"), path + ".attributes.NORMAL", TINYGLTF_TYPE_VEC3,
                             {TINYGLTF_COMPONENT_TYPE_FLOAT});
    const uint32_t materialId = material(p.material, path + ".material");
    const MaterialSpec& spec = import.specs[materialId];
    // Tangents for the normal textures, the base's or (without one) the clear coat's: the two share
    // their tangent space (KHR_materials_clearcoat says they should use the same coordinates).
    const bool normalMapped = !spec.normal.empty() || !spec.clearcoatNormalTexture.empty();
    // Without NORMAL the file's tangents are ignored (the glTF specification: the normals are the
    // faces', the tangents made from them).
    std::vector<double> tangents;
    if (normalMapped && attribute("TANGENT") >= 0 && !normals.empty())
      tangents = readAccessor(c, attribute("TANGENT"), path + ".attributes.TANGENT", TINYGLTF_TYPE_VEC4,
                              {TINYGLTF_COMPONENT_TYPE_FLOAT});
    // TEXCOORD_0, and TEXCOORD_1 where one of the material's textures reads it.
    bool readsSet1 = false;
    for (const TextureFile* f : {&spec.mapKd, &spec.metallicRoughness, &spec.normal, &spec.emissive,
                                 &spec.specularTexture, &spec.specularColourTexture, &spec.sheenColourTexture,
                                 &spec.sheenRoughnessTexture, &spec.clearcoatTexture, &spec.clearcoatRoughnessTexture,
                                 &spec.clearcoatNormalTexture, &spec.transmissionTexture})
      readsSet1 = readsSet1 || (!f->empty() && f->set == 1);
    const auto readTexcoords = [&](const std::string& name) {
      if (attribute(name.c_str()) < 0) return std::vector<double>();
      std::vector<double> read = readAccessor(c, attribute(name.c_str()), path + ".attributes." + name, TINYGLTF_TYPE_VEC2,
                                              {TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE,
                                               TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT});
      if (read.size() / 2 != vertices)
        c.fail(path + ".attributes", "its attributes differ in count from POSITION's " + std::to_string(vertices));
      return read;
    };
    texcoords = readTexcoords("TEXCOORD_0");
    const std::vector<double> colours = readColours(attribute("COLOR_0"), path + ".attributes.COLOR_0", vertices);
    const size_t colourChannels = colours.size() / vertices;
    const std::vector<double> texcoords1 = readsSet1 ? readTexcoords("TEXCOORD_1") : std::vector<double>();
    if ((!normals.empty() && normals.size() / 3 != vertices) || (!tangents.empty() && tangents.size() / 4 != vertices))
      c.fail(path + ".attributes", "its attributes differ in count from POSITION's " + std::to_string(vertices));
    // Tangents serve a normal texture only: without one they change nothing, and are not listed.
    for (const auto& [name, accessor] : p.attributes)
      if (name != "POSITION" && name != "NORMAL" && name != "TEXCOORD_0" && name != "TEXCOORD_1" && name != "TANGENT" &&
          name != "COLOR_0")
        scene.ignored.push_back(c.file + ": " + path + ".attributes." + name + " (not read)");
    if (!p.targets.empty()) scene.ignored.push_back(c.file + ": " + path + ".targets (morph targets: the base shape is rendered)");

    const std::vector<uint32_t> corners = triangleCorners(p, mode, path, vertices);

    // What the scene will hold, checked before it grows: a mesh named by many nodes is copied for each.
    if (scene.positions.size() + vertices > (uint64_t(1) << 31))
      c.fail(path, "the scene would have more than 2^31 vertices");
    const uint64_t growth = uint64_t(vertices) * kSceneBytesPerVertex + uint64_t(corners.size() / 3) * kSceneBytesPerTriangle;
    if ((grownSinceMemoryCheck += growth) >= kMemoryCheckBytes) {
      requireMemory(growth, c.file + ": " + path + "'s triangles", "render a smaller scene, or raise --memory-limit");
      grownSinceMemoryCheck = 0;
    }
    const bool mirrored = world.determinant3() < 0;  // the winding turns over
    const std::array<double, 9> normalMatrix = world.normalMatrix();
    const uint32_t first = uint32_t(scene.positions.size());
    for (size_t v = 0; v < vertices; ++v) {
      const std::array<double, 3> p3 = world.point(&positions[3 * v]);
      for (const double x : p3)
        if (!(std::abs(x) <= kMaxInputMagnitude))
          c.fail(path + ".attributes.POSITION", "vertex " + std::to_string(v) + " lies beyond 1e15 once placed by its node");
      scene.positions.push_back({float(p3[0]), float(p3[1]), float(p3[2])});
      Vec3 n{0, 0, 0};
      if (!normals.empty()) {
        const double* a = &normals[3 * v];
        const double x = normalMatrix[0] * a[0] + normalMatrix[1] * a[1] + normalMatrix[2] * a[2];
        const double y = normalMatrix[3] * a[0] + normalMatrix[4] * a[1] + normalMatrix[5] * a[2];
        const double z = normalMatrix[6] * a[0] + normalMatrix[7] * a[1] + normalMatrix[8] * a[2];
        const double len = std::sqrt(x * x + y * y + z * z) * (mirrored ? -1 : 1);
        if (len != 0 && std::isfinite(len)) n = {float(x / len), float(y / len), float(z / len)};
      }
      scene.normals.push_back(n);
      // glTF's texture coordinates (origin at the image's top left) as Lucent's, whose v runs up;
      // each texture's transform applies at lookups (Texture::transform).
      scene.texcoords.push_back(texcoords.empty() ? Vec2{0, 0}
                                                  : Vec2{float(texcoords[2 * v]), float(1 - texcoords[2 * v + 1])});
      if (readsSet1) {
        scene.texcoords1.resize(scene.positions.size() - 1);  // zeros for the vertices of meshes without
        scene.texcoords1.push_back(texcoords1.empty() ? Vec2{0, 0}
                                                      : Vec2{float(texcoords1[2 * v]), float(1 - texcoords1[2 * v + 1])});
      }
      if (!colours.empty()) {
        scene.colours.resize(scene.positions.size() - 1);  // white for the vertices of meshes without
        const double* rgba = &colours[colourChannels * v];
        scene.colours.push_back(
            {Rgb(float(rgba[0]), float(rgba[1]), float(rgba[2])), colourChannels == 4 ? float(rgba[3]) : 1.0f});
      }
    }
    if (normalMapped)
      placeTangents(tangents, world, mirrored, first, corners, spec.normal.empty() ? spec.clearcoatNormalTexture : spec.normal);
    for (size_t t = 0; t + 2 < corners.size(); t += 3) {
      uint32_t a = first + corners[t], b = first + corners[t + 1], d = first + corners[t + 2];
      if (mirrored) std::swap(b, d);
      const Vec3 p0 = scene.positions[a];
      if (!(length(cross(scene.positions[b] - p0, scene.positions[d] - p0)) > 0)) {
        ++scene.droppedDegenerateTriangles;
        continue;
      }
      scene.indices.insert(scene.indices.end(), {a, b, d});
      scene.materialIds.push_back(materialId);
    }
  }

  // The tangents of the vertices from `first` on: the file's (placed by the node's transform, the
  // sign turned over by a mirroring one), or, where it gives none or no normals, from the texture
  // coordinates, each triangle's dP/du and dP/dv summed at its corners (Lengyel's construction;
  // MikkTSpace's without its splitting of vertices), the sign where the summed bitangent lies
  // against cross(normal, tangent).
  void placeTangents(const std::vector<double>& given, const Matrix4& world, bool mirrored, uint32_t first,
                     const std::vector<uint32_t>& corners, const TextureFile& normalTexture) {
    scene.tangents.resize(scene.positions.size());
    const size_t vertices = scene.positions.size() - first;
    if (!given.empty()) {
      for (size_t v = 0; v < vertices; ++v) {
        const std::array<double, 3> d = world.direction(&given[4 * v]);
        const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        if (!(len > 0) || !std::isfinite(len)) continue;  // no frame: the vertex normal
        scene.tangents[first + v] = {{float(d[0] / len), float(d[1] / len), float(d[2] / len)},
                                     (given[4 * v + 3] < 0) != mirrored ? -1.0f : 1.0f};
      }
      return;
    }
    // The normal texture's own coordinates: its set, transformed (a rotation turns the frame).
    const std::vector<Vec2>& set = normalTexture.set == 0 ? scene.texcoords : scene.texcoords1;
    const auto uvOf = [&](uint32_t k) {
      return normalTexture.transformed ? transformedUv(normalTexture.transform.data(), set[k]) : set[k];
    };
    // Without vertex normals a face's own normal frames its normal texture (the triangle's as stored:
    // wound the other way under a mirroring node), and the faces' normals summed at a vertex decide
    // its sign.
    std::vector<Vec3> bitangents(vertices, Vec3{0, 0, 0}), faceNormals(vertices, Vec3{0, 0, 0});
    for (size_t t = 0; t + 2 < corners.size(); t += 3) {
      const uint32_t i[3] = {first + corners[t], first + corners[t + 1], first + corners[t + 2]};
      const Vec3 e1 = scene.positions[i[1]] - scene.positions[i[0]], e2 = scene.positions[i[2]] - scene.positions[i[0]];
      const Vec3 faceNormal = cross(e1, e2) * (mirrored ? -1.0f : 1.0f);
      for (const uint32_t k : i) faceNormals[k - first] = faceNormals[k - first] + faceNormal;
      const Vec2 uv0 = uvOf(i[0]), uv1 = uvOf(i[1]), uv2 = uvOf(i[2]);
      const float du1 = uv1.x - uv0.x, dv1 = uv1.y - uv0.y, du2 = uv2.x - uv0.x, dv2 = uv2.y - uv0.y;
      const float det = du1 * dv2 - du2 * dv1;
      if (!(std::abs(det) > 0) || !std::isfinite(det)) continue;
      // Unnormalized by the triangle's uv area sign only: larger triangles weigh more.
      const float s = det > 0 ? 1.0f : -1.0f;
      const Vec3 tangent = (e1 * dv2 - e2 * dv1) * s, bitangent = (e2 * du1 - e1 * du2) * s;
      for (const uint32_t k : i) {
        scene.tangents[k].direction = scene.tangents[k].direction + tangent;
        bitangents[k - first] = bitangents[k - first] + bitangent;
      }
    }
    for (size_t v = 0; v < vertices; ++v) {
      Tangent& t = scene.tangents[first + v];
      const float len = length(t.direction);
      if (!(len > 0) || !std::isfinite(len)) {
        t = {};
        continue;
      }
      t.direction = t.direction / len;
      const Vec3 n = scene.normals[first + v] == Vec3{0, 0, 0} ? faceNormals[v] : scene.normals[first + v];
      t.sign = dot(cross(n, t.direction), bitangents[v]) < 0 ? -1.0f : 1.0f;
    }
  }

  void light(int index, const std::string& path, const Matrix4& world) {
    const auto& lights = c.model.lights;
    if (index < 0 || size_t(index) >= lights.size()) c.fail(path, "light " + std::to_string(index) + " does not exist");
    const tinygltf::Light& l = lights[size_t(index)];
    const std::string lightPath = "extensions.KHR_lights_punctual.lights[" + std::to_string(index) + "]";
    Rgb colour(1.0f);
    if (!l.color.empty()) {
      if (l.color.size() != 3) c.fail(lightPath + ".color", "expected 3 numbers");
      for (int k = 0; k < 3; ++k) {
        if (!(l.color[size_t(k)] >= 0 && l.color[size_t(k)] <= 1)) c.fail(lightPath + ".color", "every value must be in [0, 1]");
        colour[k] = float(l.color[size_t(k)]);
      }
    }
    if (!(l.intensity >= 0 && l.intensity <= 1e15)) c.fail(lightPath + ".intensity", "must be in [0, 1e15]");
    // In watts the value must stay where the renderer's float arithmetic carries it: beyond, its
    // light overflows to samples that are dropped, and the image is black.
    if (!(l.intensity / lumensPerWatt <= kMaxInputMagnitude))
      c.fail(lightPath + ".intensity", quoted(l.intensity) + " at " + quoted(lumensPerWatt) +
                                           " lm/W exceeds 1e15 W");
    const Rgb value = colour * float(l.intensity / lumensPerWatt);
    if (l.range > 0) scene.ignored.push_back(c.file + ": " + lightPath + ".range (the light reaches every distance)");
    Light light;
    light.value = value;
    if (l.type == "directional") {
      const double down[3] = {0, 0, -1};
      const std::array<double, 3> d = world.direction(down);
      const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      if (!(len > 0) || !std::isfinite(len)) c.fail(path, "places the directional light with a degenerate transform");
      light.type = LightType::Directional;
      light.vector = {float(d[0] / len), float(d[1] / len), float(d[2] / len)};
    } else if (l.type == "point") {
      const double origin[3] = {0, 0, 0};
      const std::array<double, 3> p = world.point(origin);
      if (!finiteFloats(p)) c.fail(path, "places the point light beyond float range");
      light.type = LightType::Point;
      light.vector = {float(p[0]), float(p[1]), float(p[2])};
    } else if (l.type == "spot") {
      const double inner = l.spot.innerConeAngle, outer = l.spot.outerConeAngle;
      if (!(outer > 0 && outer <= kPi / 2)) c.fail(lightPath + ".spot.outerConeAngle", "must be in (0, pi/2]");
      if (!(inner >= 0 && inner < outer)) c.fail(lightPath + ".spot.innerConeAngle", "must be in [0, outerConeAngle)");
      const double origin[3] = {0, 0, 0}, down[3] = {0, 0, -1};
      const std::array<double, 3> p = world.point(origin), d = world.direction(down);
      const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      if (!(len > 0) || !std::isfinite(len) || !finiteFloats(p))
        c.fail(path, "places the spot light with a degenerate transform");
      light.type = LightType::Spot;
      light.vector = {float(p[0]), float(p[1]), float(p[2])};
      light.axis = {float(d[0] / len), float(d[1] / len), float(d[2] / len)};
      // The extension's falloff: scale 1 / max(0.001, cos(inner) - cos(outer)), offset -cos(outer) scale.
      const double scale = 1.0 / std::max(0.001, std::cos(inner) - std::cos(outer));
      light.angleScale = float(scale);
      light.angleOffset = float(-std::cos(outer) * scale);
    } else {
      c.fail(lightPath + ".type", "'" + l.type + "' is not directional, point or spot");
    }
    if (!value.isBlack()) scene.lights.push_back(light);
  }

  // The first camera in the walk, or the first named `cameraName` (its node's name or its own).
  void camera(int index, const std::string& path, const std::string& nodeName, const Matrix4& world) {
    if (content.camera) return;
    if (size_t(index) >= c.model.cameras.size()) c.fail(path + ".camera", "camera " + std::to_string(index) + " does not exist");
    const tinygltf::Camera& cam = c.model.cameras[size_t(index)];
    if (!cameraName.empty() && cam.name != cameraName && nodeName != cameraName) {
      cameraNames.push_back(nodeName.empty() ? cam.name : nodeName);
      return;
    }
    const std::string camPath = at("cameras", size_t(index));
    if (cam.type != "perspective") c.fail(camPath + ".type", "'" + cam.type + "': only perspective cameras are rendered");
    const double yfov = cam.perspective.yfov;
    // In degrees as a float too: a yfov a hair below pi rounds to 180, whose tangent is infinite.
    if (!(yfov > 0 && yfov < kPi) || !(float(yfov * 180.0 / kPi) < 180.0f))
      c.fail(camPath + ".perspective.yfov", "must be in (0, pi)");
    const double origin[3] = {0, 0, 0}, forward[3] = {0, 0, -1}, up[3] = {0, 1, 0};
    const std::array<double, 3> eye = world.point(origin), f = world.direction(forward), u = world.direction(up);
    // A transform that scales the camera to nothing (or beyond float range) leaves it no direction:
    // the directions are normalized in float, whose squares underflow below 1e-19.
    const std::array<double, 3> side = {f[1] * u[2] - f[2] * u[1], f[2] * u[0] - f[0] * u[2], f[0] * u[1] - f[1] * u[0]};
    const auto length = [](const std::array<double, 3>& v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); };
    if (!finiteFloats(eye) || !(length(f) > 1e-15 && length(u) > 1e-15 && length(side) > 1e-6 * length(f) * length(u)) ||
        !finiteFloats(f) || !finiteFloats(u))
      c.fail(path, "places camera " + std::to_string(index) + " with a degenerate transform (a scale of 0, or beyond float range)");
    Camera camera;
    camera.eye = {float(eye[0]), float(eye[1]), float(eye[2])};
    camera.lookAt = camera.eye + normalize(Vec3{float(f[0]), float(f[1]), float(f[2])});
    camera.up = normalize(Vec3{float(u[0]), float(u[1]), float(u[2])});
    camera.fovY = float(yfov * 180.0 / kPi);
    const double aspect = cam.perspective.aspectRatio > 0 ? cam.perspective.aspectRatio : 1.0;
    if (!(aspect >= 1.0 / 64 && aspect <= 64)) c.fail(camPath + ".perspective.aspectRatio", "must be in [1/64, 64]");
    camera.width = 512;
    camera.height = std::max(1, int(std::lround(512 / aspect)));
    content.camera = camera;
  }

  // Calls place(M) for each transform M at which node n places its mesh: its world transform, or
  // with EXT_mesh_gpu_instancing once per instance, the world transform times the instance's
  // T * R * S (its attributes TRANSLATION, ROTATION and SCALE, each optional, all of one count;
  // ROTATION as floats or normalized signed bytes or shorts). Each instance's triangles are checked
  // against the memory limit as they are placed (primitive), as a node's are.
  template <class Place>
  void forEachInstance(const tinygltf::Node& n, const std::string& path, const Matrix4& world, Place&& place) {
    const tinygltf::Value* e = extension(n.extensions, "EXT_mesh_gpu_instancing");
    if (!e) return place(world);
    const std::string instancing = path + ".extensions.EXT_mesh_gpu_instancing";
    if (!e->IsObject() || !e->Get("attributes").IsObject()) c.fail(instancing, "has no attributes object");
    const tinygltf::Value& attributes = e->Get("attributes");
    std::vector<double> read[3];
    const char* names[3] = {"TRANSLATION", "ROTATION", "SCALE"};
    size_t count = 0;
    for (const std::string& name : attributes.Keys()) {
      const std::string user = instancing + ".attributes." + name;
      const int k = name == names[0] ? 0 : name == names[1] ? 1 : name == names[2] ? 2 : -1;
      if (k < 0) {
        scene.ignored.push_back(c.file + ": " + user + " (not read)");
        continue;
      }
      const tinygltf::Value& index = attributes.Get(name);
      if (!index.IsInt()) c.fail(user, "is not an accessor index");
      read[k] = k == 1 ? readAccessor(c, index.GetNumberAsInt(), user, TINYGLTF_TYPE_VEC4,
                                      {TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_COMPONENT_TYPE_BYTE, TINYGLTF_COMPONENT_TYPE_SHORT})
                       : readAccessor(c, index.GetNumberAsInt(), user, TINYGLTF_TYPE_VEC3, {TINYGLTF_COMPONENT_TYPE_FLOAT});
      const size_t instances = read[k].size() / (k == 1 ? 4 : 3);
      if (count != 0 && instances != count)
        c.fail(user, "has " + std::to_string(instances) + " instances, another attribute " + std::to_string(count));
      count = instances;
      for (const double x : read[k])
        if (!std::isfinite(x)) c.fail(user, "has a non-finite value");
    }
    if (count == 0) c.fail(instancing + ".attributes", "names no TRANSLATION, ROTATION or SCALE");
    for (size_t i = 0; i < count; ++i) {
      double t[3] = {0, 0, 0}, q[4] = {0, 0, 0, 1}, s[3] = {1, 1, 1};
      if (!read[0].empty()) std::copy_n(&read[0][3 * i], 3, t);
      if (!read[1].empty()) {
        std::copy_n(&read[1][4 * i], 4, q);
        if (!normalizeQuaternion(q)) c.fail(instancing + ".attributes.ROTATION", "instance " + std::to_string(i) + " is a zero quaternion");
      }
      if (!read[2].empty()) std::copy_n(&read[2][3 * i], 3, s);
      place(world * trsMatrix(t, q, s));
    }
  }

  // glTF's nodes form disjoint strict trees: a node has one parent at most, and a scene names a
  // root once. A node reached twice (a cycle, a node shared by two parents, a root named twice) is
  // refused: followed, a file of a few kilobytes could name 2^40 instances.
  void node(int index, const Matrix4& parent, int depth, std::vector<bool>& reached) {
    const auto& nodes = c.model.nodes;
    if (index < 0 || size_t(index) >= nodes.size()) c.fail("nodes", "node " + std::to_string(index) + " does not exist");
    if (reached[size_t(index)])
      c.fail(at("nodes", size_t(index)), "is reached twice (its children lead back to it, it has two parents, or the "
                                         "scene names it twice): glTF's nodes form disjoint trees");
    if (depth > kMaxNodeDepth) c.fail(at("nodes", size_t(index)), "the hierarchy is deeper than 1024");
    reached[size_t(index)] = true;
    const tinygltf::Node& n = nodes[size_t(index)];
    const std::string path = at("nodes", size_t(index));
    const Matrix4 world = parent * nodeMatrix(c, n, path);
    if (n.mesh >= 0) {
      if (size_t(n.mesh) >= c.model.meshes.size()) c.fail(path + ".mesh", "mesh " + std::to_string(n.mesh) + " does not exist");
      const tinygltf::Mesh& mesh = c.model.meshes[size_t(n.mesh)];
      forEachInstance(n, path, world, [&](const Matrix4& placed) {
        for (size_t k = 0; k < mesh.primitives.size(); ++k)
          primitive(mesh.primitives[k], at("meshes", size_t(n.mesh)) + "." + at("primitives", k), placed);
      });
    }
    if (n.skin >= 0) scene.ignored.push_back(c.file + ": " + path + ".skin (the bind pose is rendered)");
    if (n.camera >= 0) camera(n.camera, path, n.name, world);
    if (const tinygltf::Value* e = extension(n.extensions, "KHR_lights_punctual"))
      light(int(number(*e, "light", -1)), path + ".extensions.KHR_lights_punctual.light", world);
    for (const int child : n.children) node(child, world, depth + 1, reached);
  }
};

// The files TinyGLTF reads (the .gltf or .glb, external buffers and images): regular files only, of
// at most kMaxFileBytes, read whole; paths taken as they are written (no expansion); nothing
// written. Each file read is added to the scene's inputs (`user`: its inputFiles) by the path
// TinyGLTF opened, after its own decoding of the URI and joining it to the file's folder.
constexpr uint64_t kMaxFileBytes = uint64_t(1) << 32;
bool regularFileExists(const std::string& path, void*) { return regularFileProblem(path).empty(); }
std::string pathAsWritten(const std::string& path, void*) { return path; }
bool readRegularFile(std::vector<unsigned char>* out, std::string* error, const std::string& path, void* user) {
  const std::string problem = admitInputFile(path);
  std::error_code ec;
  const uint64_t size = problem.empty() ? uint64_t(fs::file_size(path, ec)) : 0;
  if (!problem.empty() || ec || size > kMaxFileBytes) {
    if (error) *error += path + (problem.empty() ? " is larger than 4 GiB" : " " + problem) + "\n";
    return false;
  }
  std::ifstream in(path, std::ios::binary);
  out->resize(size_t(size));
  if (!in.read(reinterpret_cast<char*>(out->data()), std::streamsize(size))) {
    if (error) *error += path + ": cannot be read\n";
    return false;
  }
  static_cast<std::vector<std::string>*>(user)->push_back(path);
  return true;
}
bool writeNothing(std::string* error, const std::string&, const std::vector<unsigned char>&, void*) {
  if (error) *error += "writing is not allowed\n";
  return false;
}

// Images are not decoded while the file is read: an image named by a URI keeps its file's bytes, for
// the loader's own image reader; one in a buffer view is read from the view once it is checked
// (TinyGLTF hands such images over without checking the view against its buffer).
bool keepImageBytes(tinygltf::Image* image, const int, std::string*, std::string*, int, int, const unsigned char* bytes,
                    int size, void*) {
  if (image->bufferView < 0 && bytes && size > 0) image->image.assign(bytes, bytes + size);
  return true;
}

}  // namespace

void importGltf(const std::string& path, const GltfOptions& options, Scene& scene, ObjImport& import,
                GltfContent& content) {
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(keepImageBytes, nullptr);
  loader.SetFsCallbacks({regularFileExists, pathAsWritten, readRegularFile, writeNothing, &scene.inputFiles});
  tinygltf::Model model;
  std::string error, warning;
  const bool binary = fs::path(path).extension() == ".glb";
  const bool read = binary ? loader.LoadBinaryFromFile(&model, &error, &warning, path)
                           : loader.LoadASCIIFromFile(&model, &error, &warning, path);
  if (!read) {
    std::string first = error.substr(0, error.find('\n'));
    if (first.size() > 200) first = first.substr(0, 200) + "...";
    throw SceneError(path + ": not a readable glTF file: " + (first.empty() ? "unknown error" : first));
  }
  const Context c{model, path, warning};
  for (const std::string& name : model.extensionsRequired)
    if (!kSupportedExtensions.count(name))
      c.fail("extensionsRequired", "names " + name + ", which Lucent does not render");
  for (const std::string& name : model.extensionsUsed)
    if (!kSupportedExtensions.count(name)) scene.ignored.push_back(path + ": extension " + name + " (not read)");

  if (model.scenes.empty()) c.fail("scenes", "the file has no scene");
  const size_t sceneIndex = model.defaultScene >= 0 ? size_t(model.defaultScene) : 0;
  if (sceneIndex >= model.scenes.size()) c.fail("scene", "scene " + std::to_string(sceneIndex) + " does not exist");
  NodeWalk walk{c, scene, import, content, options.lumensPerWatt, options.camera, {}, options.heightCorrelated ? GgxMasking::HeightCorrelated : GgxMasking::Separable,
                options.bendNormalMaps, {}, 0};
  std::vector<bool> reached(model.nodes.size(), false);
  for (const int root : model.scenes[sceneIndex].nodes) walk.node(root, Matrix4{}, 0, reached);
  if (!options.camera.empty() && !content.camera) {
    std::string names;
    for (const std::string& name : walk.cameraNames) names += (names.empty() ? "" : ", ") + ("'" + name + "'");
    c.fail("cameras", "no camera in the scene is named '" + options.camera + "' (" +
                          (names.empty() ? std::string("it has none") : "it has " + names) + ")");
  }
  if (walk.skippedPrimitives > 0)
    scene.ignored.push_back(path + ": " + std::to_string(walk.skippedPrimitives) + " point and line primitives");
}

}  // namespace lucent::detail
