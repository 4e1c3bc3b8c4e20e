// lucent bsdf SCENE [MATERIAL]: a material's scattering without rendering, for a backend author to
// hold their BSDF to. Without MATERIAL, the scene's materials (index, name, type). With it (a name,
// or an index), its directional albedo E(cos theta) per channel at --cosines angles, with standard
// errors, and with --wo and --wi the BSDF's value and sampling density for that pair of directions;
// as CSV, or JSON with --json. The material's factors are used; textures and vertex colours that
// would scale them are listed as not read.
#include <iomanip>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cli/commands.h"
#include "core/json_text.h"
#include "lucent/core/text.h"
#include "lucent/scene/bsdf_albedo.h"
#include "lucent/scene/loader.h"
#include "lucent/scene/surface.h"

namespace lucent::cli {

namespace {

// Its kind, and for a GGX lobe the masking form.
std::string typeName(const Material& m) {
  std::string name = materialTypeName(m.type);
  if (m.type == MaterialType::Gltf)
    name += m.masking == GgxMasking::Separable ? " (separable masking)" : " (height-correlated masking)";
  return name;
}

struct BsdfArgs {
  std::string scene, material;
  int cosines = 16;
  uint32_t samples = 1u << 20;
  uint64_t seed = 0;
  std::vector<double> wo, wi;
  bool json = false;
};

// The material MATERIAL names: by name, else as an index.
uint32_t findMaterial(const Scene& scene, const std::string& material) {
  for (uint32_t i = 0; i < scene.materialNames.size(); ++i)
    if (scene.materialNames[i] == material) return i;
  if (!material.empty() && material.find_first_not_of("0123456789") == std::string::npos && material.size() < 10 &&
      std::stoul(material) < scene.materials.size())
    return uint32_t(std::stoul(material));
  throw std::invalid_argument("'" + material + "' is neither the name nor the index of one of the scene's " +
                              std::to_string(scene.materials.size()) + " materials (lucent bsdf SCENE lists them)");
}

// What scales the material's factors at a surface point and is not read here.
std::vector<std::string> notRead(const Scene& scene, const Material& m) {
  std::vector<std::string> out;
  if (m.kdTexture >= 0) out.push_back("base colour texture");
  if (m.metallicRoughnessTexture >= 0) out.push_back("metallic-roughness texture");
  if (m.specularTexture >= 0) out.push_back("specular texture");
  if (m.specularColorTexture >= 0) out.push_back("specular colour texture");
  if (m.sheenColourTexture >= 0) out.push_back("sheen colour texture");
  if (m.sheenRoughnessTexture >= 0) out.push_back("sheen roughness texture");
  if (m.clearcoatTexture >= 0) out.push_back("clearcoat texture");
  if (m.clearcoatRoughnessTexture >= 0) out.push_back("clearcoat roughness texture");
  if (m.normalTexture >= 0) out.push_back("normal texture");
  if (m.clearcoatNormalTexture >= 0) out.push_back("clearcoat normal texture");
  if (m.transmissionTexture >= 0) out.push_back("transmission texture");
  if (!scene.colours.empty()) out.push_back("vertex colours");
  return out;
}

Vec3 unitDirection(const std::vector<double>& v, const char* flag) {
  const Vec3 d{float(v[0]), float(v[1]), float(v[2])};
  if (!(length(d) > 0) || !std::isfinite(length(d)))
    throw std::invalid_argument(std::string(flag) + ": not a direction (its length is 0 or not finite)");
  return normalize(d);
}

int runBsdf(const BsdfArgs& a) {
  const Scene scene = loadScene(a.scene, {true});
  if (a.material.empty()) {
    nlohmann::ordered_json list = nlohmann::ordered_json::array();
    for (uint32_t i = 0; i < scene.materials.size(); ++i) {
      if (a.json) list.push_back({{"index", i}, {"name", scene.materialNames[i]}, {"type", typeName(scene.materials[i])}});
      else std::cout << i << "," << printable(scene.materialNames[i]) << "," << typeName(scene.materials[i]) << "\n";
    }
    if (a.json) std::cout << jsonText(list) << std::endl;
    return 0;
  }
  if (a.wo.empty() != a.wi.empty()) throw std::invalid_argument("--wo and --wi: give both, or neither");
  const uint32_t index = findMaterial(scene, a.material);
  const Material& m = scene.materials[index];
  const SurfaceBsdf bsdf = materialBsdf(m);
  nlohmann::ordered_json out = {{"scene", a.scene},         {"material", scene.materialNames[index]},
                                {"index", index},            {"type", typeName(m)},
                                {"not_read", notRead(scene, m)}, {"samples", a.samples},
                                {"seed", a.seed}};
  std::ostringstream csv;
  csv << std::setprecision(7) << "cos_theta,albedo_r,albedo_g,albedo_b,error_r,error_g,error_b\n";
  nlohmann::ordered_json albedo = nlohmann::ordered_json::array();
  // From grazing to normal incidence (for a lobe with an inside, glass, also from there, cos theta < 0;
  // a two-sided one is only ever seen from above).
  const bool inside = has(bsdf.flags(), BsdfFlags::Transmission) && !twoSidedShading(bsdf);
  for (int k = inside ? -a.cosines : 0; k < a.cosines; ++k) {
    const float cosTheta = float((k + 0.5) / a.cosines);
    const AlbedoEstimate e = directionalAlbedo(bsdf, cosTheta, a.samples, a.seed);
    albedo.push_back({{"cos_theta", cosTheta},
                      {"albedo", {e.albedo.r, e.albedo.g, e.albedo.b}},
                      {"standard_error", {e.standardError.r, e.standardError.g, e.standardError.b}}});
    csv << cosTheta << "," << e.albedo.r << "," << e.albedo.g << "," << e.albedo.b << "," << e.standardError.r << ","
        << e.standardError.g << "," << e.standardError.b << "\n";
  }
  out["directional_albedo"] = albedo;
  if (!a.wo.empty()) {
    const Vec3 wo = unitDirection(a.wo, "--wo"), wi = unitDirection(a.wi, "--wi");
    const BsdfValue v = evalBsdfAndPdf(bsdf, wo, wi);
    out["wo"] = {wo.x, wo.y, wo.z}, out["wi"] = {wi.x, wi.y, wi.z};
    out["f"] = {v.f.r, v.f.g, v.f.b}, out["pdf"] = v.pdf;
    csv << "\nwo_x,wo_y,wo_z,wi_x,wi_y,wi_z,f_r,f_g,f_b,pdf\n"
        << wo.x << "," << wo.y << "," << wo.z << "," << wi.x << "," << wi.y << "," << wi.z << "," << v.f.r << ","
        << v.f.g << "," << v.f.b << "," << v.pdf << "\n";
  }
  if (a.json) std::cout << jsonText(out) << std::endl;
  else std::cout << csv.str() << std::flush;
  return 0;
}

}  // namespace

void addBsdfCommand(CLI::App& app, int& exitCode) {
  auto args = std::make_shared<BsdfArgs>();
  CLI::App* cmd = app.add_subcommand(
      "bsdf", "a material's directional albedo, and its BSDF value and density for given directions, without "
              "rendering (factors only: textures are listed as not read)");
  cmd->add_option("scene", args->scene, "scene file (JSON) or glTF file")->required();
  cmd->add_option("material", args->material, "a material's name or index (none: list the scene's materials)");
  cmd->add_option("--cosines", args->cosines, "angles of incidence: cos theta = (k + 0.5) / N, k = 0 .. N - 1")
      ->capture_default_str()->check(CLI::Range(1, 1024));
  cmd->add_option("--samples", args->samples, "BSDF samples per angle")->capture_default_str()->check(CLI::Range(2u, 1u << 30));
  cmd->add_option("--seed", args->seed, "keys the samples' random numbers")->capture_default_str();
  cmd->add_option("--wo", args->wo, "outgoing direction x,y,z in the shading frame (normal +z): with --wi, prints f and pdf")
      ->delimiter(',')->expected(3);
  cmd->add_option("--wi", args->wi, "incident direction x,y,z in the shading frame")->delimiter(',')->expected(3);
  cmd->add_flag("--json", args->json, "as JSON instead of CSV");
  cmd->callback([args, &exitCode] { exitCode = runBsdf(*args); });
}

}  // namespace lucent::cli
