#include "lucent/methods/methods.h"

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

}  // namespace lucent
