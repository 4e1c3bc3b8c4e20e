#include "cli/method_options.h"

#include <sstream>

#include "lucent/methods/methods.h"

namespace lucent::cli {

namespace {

const OptionSpec* anySpec(const std::string& name) {
  for (const Method* m : renderingMethods())
    for (const OptionSpec& spec : m->options())
      if (spec.name == name) return &spec;
  return nullptr;
}

std::string optionName(const std::string& flag) {
  std::string name = flag.substr(2);
  for (char& c : name)
    if (c == '-') c = '_';
  return name;
}

std::string valuePlaceholder(const OptionSpec& spec) {
  if (!spec.placeholder.empty()) return spec.placeholder;
  switch (spec.kind) {
    case OptionKind::Integer: return "N";
    case OptionKind::Real: return "X";
    case OptionKind::Flag: return "";
    case OptionKind::Choice: {
      std::string c;
      for (const std::string& choice : spec.choices) c += (c.empty() ? "" : "|") + choice;
      return c;
    }
    case OptionKind::Text: return "DIR";
    case OptionKind::Triple: return "XxYxZ";
  }
  return "";
}

}  // namespace

std::string flagOf(const std::string& option) {
  OptionSpec spec;
  spec.name = option;
  return spec.flag();
}

std::pair<std::string, std::string> methodOptionArg(const std::string& key, const std::optional<std::string>& inlineValue,
                                                    const std::optional<std::string>& next,
                                                    const std::function<std::string()>& takeNext) {
  const std::string name = optionName(key);
  if (const OptionSpec* spec = anySpec(name)) {
    if (inlineValue) return {name, *inlineValue};
    if (spec->kind != OptionKind::Flag) return {name, takeNext()};
    if (next && (*next == "true" || *next == "false")) return {name, takeNext()};
    return {name, "true"};
  }
  if (name.rfind("no_", 0) == 0 && !inlineValue)
    if (const OptionSpec* spec = anySpec(name.substr(3)); spec && spec->kind == OptionKind::Flag)
      return {spec->name, "false"};
  throw std::invalid_argument("unknown option " + key + " (lucent methods lists every method's options)");
}

nlohmann::ordered_json methodOptionsJson(const Method& method, const OptionValues& resolved) {
  return nlohmann::ordered_json::parse(optionsJsonText(method.options(), resolved));
}

std::string optionsHelp(const std::vector<OptionSpec>& options) {
  std::ostringstream out;
  for (const OptionSpec& spec : options) {
    const std::string value = valuePlaceholder(spec);
    out << "  " << (spec.shortFlag.empty() ? "" : spec.shortFlag + ", ") << spec.flag() << (value.empty() ? "" : " " + value)
        << "\n      " << spec.help << "\n      ";
    if (spec.kind == OptionKind::Integer || spec.kind == OptionKind::Real || spec.kind == OptionKind::Triple) {
      std::string range = rangeText(spec.min, spec.max, spec.kind);  // "must be in [a, b]" or "must be ..."
      range = range.rfind("must be in ", 0) == 0 ? range.substr(11) : range.substr(8);
      out << range << (spec.unit.empty() ? "" : " " + spec.unit) << ", ";
    } else if (!spec.unit.empty()) {
      out << spec.unit << ", ";
    }
    out << "default " << (spec.defaultText.empty() ? "none" : spec.defaultText) << "\n";
  }
  return out.str();
}

}  // namespace lucent::cli
