#include "lucent/render/dump_records.h"

#include <stdexcept>

namespace lucent {

uint32_t dumpFieldBytes(DumpFieldKind k) {
  switch (k) {
    case DumpFieldKind::F16: case DumpFieldKind::U16: return 2;
    case DumpFieldKind::U64: return 8;
    default: return 4;
  }
}

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
        {"ShadingPoint", {128, {{"position", K::F32, 3}, {"geometric_normal", K::F32, 3}, {"normal", K::F32, 3}, {"wo", K::F32, 3},
                                {"weight", K::F32, 3}, {"material", K::U32, 1}, {"kd", K::F32, 3}, {"ks", K::F32, 3},
                                {"ns", K::F32, 1}, {"ni", K::F32, 1}, {"alpha", K::F32, 1}, {"f90", K::F32, 1},
                                {"dielectric_f0", K::F32, 1}, {"dielectric_f90", K::F32, 1}, {"pixel", K::U32, 1},
                                {"sample", K::U32, 1}, {"branch", K::U32, 1}, {"triangle", K::U32, 1}}, false}},
    };
    for (const auto& [name, type] : t) {
      uint32_t bytes = 0;
      for (const DumpField& f : type.fields) bytes += dumpFieldBytes(f.kind) * f.count;
      if (bytes != type.bytes) throw std::logic_error("dump records: the fields of " + name + " do not add up to its size");
    }
    return t;
  }();
  return types;
}

uint32_t dumpFieldOffset(const std::string& type, const std::string& field) {
  uint32_t offset = 0;
  for (const DumpField& f : dumpRecordTypes().at(type).fields) {
    if (field == f.name) return offset;
    offset += dumpFieldBytes(f.kind) * f.count;
  }
  throw std::logic_error("dump record type " + type + " has no field " + field);
}

}  // namespace lucent
