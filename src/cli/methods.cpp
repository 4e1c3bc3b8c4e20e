// lucent methods [NAME] [--json]: every rendering method (or one) with its options, their ranges,
// units, defaults and help, from the methods' declarations.
#include <iostream>
#include <nlohmann/json.hpp>

#include "cli/commands.h"
#include "cli/method_options.h"
#include "lucent/methods/methods.h"

namespace lucent::cli {

namespace {

const char* kindName(OptionKind kind) {
  switch (kind) {
    case OptionKind::Integer: return "integer";
    case OptionKind::Real: return "real";
    case OptionKind::Flag: return "flag";
    case OptionKind::Choice: return "choice";
    case OptionKind::Text: return "text";
    case OptionKind::Triple: return "triple";
  }
  return "?";
}

nlohmann::ordered_json methodJson(const Method& m) {
  nlohmann::ordered_json options = nlohmann::ordered_json::array();
  for (const OptionSpec& spec : m.options()) {
    nlohmann::ordered_json o = {{"name", spec.name}, {"flag", spec.flag()}, {"kind", kindName(spec.kind)}};
    if (spec.kind == OptionKind::Integer || spec.kind == OptionKind::Real || spec.kind == OptionKind::Triple)
      o["min"] = spec.min, o["max"] = spec.max;
    if (spec.kind == OptionKind::Choice) o["choices"] = spec.choices;
    o["unit"] = spec.unit;
    o["default"] = methodOptionsJson(m, {{spec.name, spec.defaultText}})[spec.name];
    o["help"] = spec.help;
    options.push_back(o);
  }
  return {{"name", m.name()}, {"summary", m.summary()}, {"options", options}};
}

}  // namespace

void addMethodsCommand(CLI::App& app, int& exitCode) {
  struct Args {
    std::string name;
    bool json = false;
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand("methods", "List the rendering methods with their options and defaults");
  cmd->add_option("name", args->name, "Only this method");
  cmd->add_flag("--json", args->json, "As JSON");
  cmd->callback([args, &exitCode] {
    std::vector<const Method*> methods = renderingMethods();
    if (!args->name.empty()) methods = {&renderingMethod(args->name)};
    if (args->json) {
      nlohmann::ordered_json out = nlohmann::ordered_json::array();
      for (const Method* m : methods) out.push_back(methodJson(*m));
      std::cout << out.dump(2) << std::endl;
    } else {
      for (const Method* m : methods)
        std::cout << m->name() << ": " << m->summary() << "\n" << optionsHelp(m->options()) << "\n";
    }
    exitCode = 0;
  });
}

}  // namespace lucent::cli
