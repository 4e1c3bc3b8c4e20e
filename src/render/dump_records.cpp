#include "lucent/render/dump_records.h"

#include <algorithm>
#include <cstddef>
#include <deque>

#include "lucent/pipeline/shading_points.h"
#include <stdexcept>

namespace lucent {

uint32_t dumpFieldBytes(DumpFieldKind k) {
  switch (k) {
    case DumpFieldKind::F16: case DumpFieldKind::U16: return 2;
    case DumpFieldKind::U64: return 8;
    default: return 4;
  }
}

namespace {

// A shading point's fields, its BSDF's lobe as the union it is: each kind's members (the lobe
// header's `fields`, named KIND_FIELD) from the union's first byte, for every kind a shading point
// can hold (none that is only specular).
std::vector<DumpField> shadingPointFields() {
  using K = DumpFieldKind;
  static std::deque<std::string> names;  // the composed names, kept for DumpField::name
  std::vector<DumpField> out = {{"position", K::F32, 3}, {"geometric_normal", K::F32, 3}, {"normal", K::F32, 3},
                                {"wo", K::F32, 3},       {"weight", K::F32, 3},           {"material", K::U32, 1}};
  const auto lobe = int32_t(offsetof(ShadingPoint, bsdf) + offsetof(SurfaceBsdf, lambertian));
#define LUCENT_LOBE_FIELDS(kind, value, Lobe, member, kindName, sceneFile)                                  \
  if (!onlySpecular(Lobe::flags))                                                                    \
    for (const LobeField& f : Lobe::fields) {                                                        \
      names.push_back(std::string(#member) + "_" + f.name);                                         \
      out.push_back({names.back().c_str(), f.isFloat ? K::F32 : K::U32, f.count, 0, &f == Lobe::fields ? lobe : -1}); \
    }
  LUCENT_MATERIAL_KINDS(LUCENT_LOBE_FIELDS)
#undef LUCENT_LOBE_FIELDS
  const auto after = int32_t(lobe + SurfaceBsdf::kLobeBytes);
  out.insert(out.end(), {{"pixel", K::U32, 1, 0, after}, {"sample", K::U32, 1}, {"branch", K::U32, 1}, {"triangle", K::U32, 1},
                          {"medium", K::U32, 1}});
  return out;
}

}  // namespace

const std::map<std::string, DumpRecordType>& dumpRecordTypes() {
  using K = DumpFieldKind;
  static const std::map<std::string, DumpRecordType> types = [] {
    std::map<std::string, DumpRecordType> t = {
        {"uint32", {4, {{"value", K::U32, 1}}, true}},
        {"uint64", {8, {{"value", K::U64, 1}}, true}},
        {"float", {4, {{"value", K::F32, 1}}, false}},
        {"Rgb", {12, {{"rgb", K::F32, 3}}, false}},
        {"HalfRgb", {6, {{"rgb", K::F16, 3}}, false}},
        {"Photon", {32, {{"position", K::F32, 3}, {"power", K::F32, 3}, {"direction", K::U32, 1}, {"flags", K::U32, 1}}, false}},
        {"PhotonDistance", {8, {{"d2", K::F32, 1}, {"index", K::U32, 1}}, false}},
        {"UniformGrid", {64, {{"lo", K::F32, 3}, {"hi", K::F32, 3}, {"cell_size", K::F32, 3}, {"inv_cell_size", K::F32, 3},
                              {"res", K::I32, 3}, {"slack", K::F32, 1}}, true}},
        {"DirectionalRadiance", {96, {{"shown", K::F32, 18, 3}, {"area", K::F32, 6}}, false}},
        {"PointSample", {12, {{"triangle", K::U32, 1}, {"b1", K::F32, 1}, {"b2", K::F32, 1}}, false}},
        {"FloatNode", {44, {{"center", K::F32, 3}, {"radius", K::F32, 1}, {"cone_axis", K::F32, 3}, {"cone_angle", K::F32, 1},
                            {"albedo", K::F32, 3}}, false}},
        {"PackedNode", {16, {{"position", K::U16, 3}, {"radius", K::U16, 1}, {"normal_albedo", K::U32, 1}, {"cone_free", K::U32, 1}}, true}},
        {"NodeQuantization", {28, {{"origin", K::F32, 3}, {"step", K::F32, 3}, {"radius_step", K::F32, 1}}, false}},
        {"EnvPointNode", {48, {{"position", K::F32, 3}, {"radius", K::F32, 1}, {"normal", K::F32, 3}, {"cone_angle", K::F32, 1},
                               {"child", K::U32, 2}, {"skip", K::U32, 1}, {"selection", K::U32, 1}}, false}},
        {"Surfel", {24, {{"position", K::F32, 3}, {"normal", K::F32, 3}}, false}},
        {"RadianceCache", {628, {{"position", K::F32, 3}, {"normal", K::F32, 3}, {"radius", K::F32, 1},
                                 {"environment", K::F32, 75, 3}, {"indirect", K::F32, 75, 3}}, false}},
        {"AreaParticle", {44, {{"position", K::F32, 3}, {"normal", K::F32, 3}, {"area", K::F32, 1}, {"reflectance", K::F32, 3},
                               {"triangle", K::U32, 1}}, false}},
        {"TriangleTessellation", {8, {{"first", K::U32, 1}, {"segments", K::U32, 1}}, true}},
        {"ShadingPoint", {uint32_t(sizeof(ShadingPoint)), shadingPointFields(), false}},
    };
    // Every byte of a record is some field's: no gaps, nothing past its end.
    for (const auto& [name, type] : t) {
      std::vector<bool> covered(type.bytes, false);
      const std::vector<uint32_t> offsets = dumpFieldOffsets(type);
      for (size_t i = 0; i < type.fields.size(); ++i)
        for (uint32_t b = 0; b < dumpFieldBytes(type.fields[i].kind) * type.fields[i].count; ++b) {
          if (offsets[i] + b >= type.bytes) throw std::logic_error("dump records: a field of " + name + " ends past its size");
          covered[offsets[i] + b] = true;
        }
      if (std::find(covered.begin(), covered.end(), false) != covered.end())
        throw std::logic_error("dump records: the fields of " + name + " leave bytes uncovered");
    }
    return t;
  }();
  return types;
}

std::vector<uint32_t> dumpFieldOffsets(const DumpRecordType& type) {
  std::vector<uint32_t> out;
  uint32_t next = 0;
  for (const DumpField& f : type.fields) {
    out.push_back(f.at >= 0 ? uint32_t(f.at) : next);
    next = out.back() + dumpFieldBytes(f.kind) * f.count;
  }
  return out;
}

uint32_t dumpFieldOffset(const std::string& type, const std::string& field) {
  const DumpRecordType& t = dumpRecordTypes().at(type);
  const std::vector<uint32_t> offsets = dumpFieldOffsets(t);
  for (size_t i = 0; i < t.fields.size(); ++i)
    if (field == t.fields[i].name) return offsets[i];
  throw std::logic_error("dump record type " + type + " has no field " + field);
}

}  // namespace lucent
