// The command line's view of the methods' declared options: flags from names and back, checks that
// name the method an option belongs to, typed JSON, and help text (lucent render, lucent methods).
#pragma once
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>

#include "lucent/pipeline/method.h"

namespace lucent::cli {

// "--gather-rays" for "gather_rays".
std::string flagOf(const std::string& option);

// A method option as given: `--name VALUE`, `--name=VALUE`, and for flags `--name` (true),
// `--name true|false` and `--no-name` (false). Whether the option takes a value is known from any
// method that declares it; a name no method declares is an error. `next` is the argument after the
// key, if any; `takeNext` consumes it.
std::pair<std::string, std::string> methodOptionArg(const std::string& key, const std::optional<std::string>& inlineValue,
                                                    const std::optional<std::string>& next,
                                                    const std::function<std::string()>& takeNext);

// The options as a JSON object: numbers, true or false, and strings, by each option's kind.
nlohmann::ordered_json methodOptionsJson(const Method& method, const OptionValues& resolved);

// One entry per option: the flag and its values, then the help, unit, range and default.
std::string optionsHelp(const std::vector<OptionSpec>& options);

}  // namespace lucent::cli
