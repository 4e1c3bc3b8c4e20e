#include "lucent/methods/methods.h"

#include <algorithm>
#include <filesystem>
#include <stdexcept>

#include "lucent/methods/envpbgi.h"
#include "lucent/methods/microrender.h"
#include "lucent/methods/particles.h"
#include "lucent/methods/pathtrace.h"
#include "lucent/methods/photonmap.h"

namespace lucent {

const std::vector<const Method*>& renderingMethods() {
  static const std::vector<const Method*> methods = {&pathTraceMethod(), &purcellMethod(), &pmfgMethod(),
                                                     &microMethod(), &envPbgiMethod(),
                                                     &particlesMethod()};
  return methods;
}

const Method& renderingMethod(const std::string& name) {
  std::string names;
  for (const Method* m : renderingMethods()) {
    if (m->name() == name) return *m;
    names += (names.empty() ? "" : ", ") + m->name();
  }
  throw std::invalid_argument("unknown method '" + name + "' (available: " + names + ")");
}

const Method* methodWithOption(const std::string& option, const Method* except) {
  for (const Method* m : renderingMethods()) {
    if (m == except) continue;
    for (const OptionSpec& spec : m->options())
      if (spec.name == option) return m;
  }
  return nullptr;
}

void checkMethodOption(const Method& method, const std::string& name, const std::string& where) {
  for (const OptionSpec& spec : method.options())
    if (spec.name == name) return;
  if (const Method* other = methodWithOption(name, &method))
    throw std::invalid_argument(where + ": an option of --method " + other->name() + ", not of --method " +
                                method.name());
  throw std::invalid_argument(where + ": not an option of --method " + method.name());
}

OptionValues sceneRenderBlockOptions(const Scene& scene, const Method& method, std::vector<std::string>& origins) {
  OptionValues values;
  if (!scene.render.present || (!scene.render.method.empty() && scene.render.method != method.name())) return values;
  for (const auto& [name, text] : scene.render.options) {
    const std::string origin = scene.sourcePath + ": render." + name;
    checkMethodOption(method, name, origin);
    for (const OptionSpec& spec : method.options())
      if (spec.name == name && spec.kind == OptionKind::Text)
        throw std::invalid_argument(origin + ": a scene file cannot choose where Lucent writes; give " + spec.flag() +
                                    " on the command line (or " + name + "= in Python)");
    values.emplace_back(name, text);
    origins.push_back(origin);
  }
  return values;
}

void checkOutputDirectories(const Method& method, const OptionValues& resolved, const Scene& scene) {
  namespace fs = std::filesystem;
  for (const auto& value : resolved) {
    const std::string& directory = value.second;
    const auto spec = std::find_if(method.options().begin(), method.options().end(),
                                   [&](const OptionSpec& s) { return s.name == value.first; });
    if (directory.empty() || spec == method.options().end() || spec->kind != OptionKind::Text) continue;
    for (const std::string& input : scene.inputFiles) {
      std::error_code ec;
      // A dump's arrays (*.bin) and its settings (settings.json) would replace the input there.
      const bool dumpName = fs::path(input).extension() == ".bin" || fs::path(input).filename() == "settings.json";
      if (dumpName && fs::equivalent(fs::absolute(input).parent_path(), directory, ec))
        throw std::invalid_argument(spec->flag() + " '" + directory + "' holds '" + input +
                                    "', a file the scene reads, under a dump file's name; choose another directory");
    }
  }
}

}  // namespace lucent
