#include "lucent/pipeline/options.h"

#include <charconv>
#include <cmath>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/json_text.h"

namespace lucent {

std::string OptionSpec::flag() const {
  std::string f = "--" + name;
  for (char& c : f)
    if (c == '_') c = '-';
  return f;
}

namespace {

// 2^n for powers of two from 2^10 on (limits such as 1 << 28 read better so), else the number.
std::string boundText(double v) {
  if (v >= 1024 && std::floor(v) == v) {
    const int e = int(std::lround(std::log2(v)));
    if (std::ldexp(1.0, e) == v) return "2^" + std::to_string(e);
  }
  return optionText(v, OptionKind::Real);
}

}  // namespace

std::string optionText(double value, OptionKind kind) {
  if (kind == OptionKind::Flag) return value != 0 ? "true" : "false";
  if (kind == OptionKind::Integer) return std::to_string(int64_t(value));
  char buffer[32];
  // The shortest text that reads back as the same float; options are floats or doubles, and a
  // float's shortest form is what one expects to see (0.1, not 0.10000000149).
  const float f = float(value);
  const auto [end, ec] = double(f) == value ? std::to_chars(buffer, buffer + sizeof buffer, f)
                                            : std::to_chars(buffer, buffer + sizeof buffer, value);
  return ec == std::errc() ? std::string(buffer, end) : std::string("?");
}

std::string rangeText(double min, double max, OptionKind kind) {
  if (kind == OptionKind::Real && min == 0 && !(max < 1e30)) return "must be finite and not negative";
  return "must be in [" + boundText(min) + ", " + boundText(max) + "]";
}

int64_t parseOptionInteger(const std::string& option, std::string_view text, double min, double max) {
  int64_t value = 0;
  const char* first = text.data() + (text.size() > 1 && text[0] == '+' ? 1 : 0);
  const auto [end, ec] = std::from_chars(first, text.data() + text.size(), value);
  if (ec == std::errc::result_out_of_range || (ec == std::errc() && end == text.data() + text.size() &&
                                               (double(value) < min || double(value) > max)))
    throw OptionError(option, "'" + std::string(text) + "' " + rangeText(min, max, OptionKind::Integer));
  if (ec != std::errc() || end != text.data() + text.size() || text.empty())
    throw OptionError(option, "'" + std::string(text) + "' is not a whole number");
  return value;
}

double parseOptionReal(const std::string& option, std::string_view text, double min, double max, bool asFloat) {
  double value = 0;
  const char* first = text.data() + (text.size() > 1 && text[0] == '+' ? 1 : 0);
  const auto [end, ec] = std::from_chars(first, text.data() + text.size(), value);
  if (ec != std::errc() || end != text.data() + text.size() || text.empty() || !std::isfinite(value)) {
    if (ec == std::errc::result_out_of_range)
      throw OptionError(option, "'" + std::string(text) + "' " + rangeText(min, max, OptionKind::Real));
    throw OptionError(option, "'" + std::string(text) + "' is not a finite number");
  }
  if (!(asFloat ? realInRange<float>(value, min, max) : realInRange<double>(value, min, max)))
    throw OptionError(option, "'" + std::string(text) + "' " + rangeText(min, max, OptionKind::Real));
  return value;
}

bool parseOptionFlag(const std::string& option, std::string_view text) {
  if (text == "true" || text == "1" || text == "yes" || text == "on") return true;
  if (text == "false" || text == "0" || text == "no" || text == "off") return false;
  throw OptionError(option, "'" + std::string(text) + "' is not true or false");
}

std::array<uint32_t, 3> parseOptionTriple(const std::string& option, std::string_view text, double min, double max) {
  std::array<uint32_t, 3> value{0, 0, 0};
  if (text == "auto" || text == "0x0x0") return value;
  size_t at = 0;
  for (int axis = 0; axis < 3; ++axis) {
    const size_t x = axis < 2 ? text.find('x', at) : text.size();
    if (x == std::string_view::npos)
      throw OptionError(option, "'" + std::string(text) + "': expected three whole numbers XxYxZ, e.g. 25x25x50");
    int64_t v = 0;
    const std::string_view part = text.substr(at, x - at);
    const auto [end, ec] = std::from_chars(part.data(), part.data() + part.size(), v);
    if (ec != std::errc() || end != part.data() + part.size() || part.empty())
      throw OptionError(option, "'" + std::string(text) + "': expected three whole numbers XxYxZ, e.g. 25x25x50");
    if (double(v) < min || double(v) > max)
      throw OptionError(option, "'" + std::string(text) + "': each count " + rangeText(min, max, OptionKind::Integer));
    value[size_t(axis)] = uint32_t(v);
    at = x + 1;
  }
  return value;
}

std::string tripleText(const std::array<uint32_t, 3>& value) {
  if (value[0] == 0 && value[1] == 0 && value[2] == 0) return "auto";
  std::ostringstream s;
  s << value[0] << 'x' << value[1] << 'x' << value[2];
  return s.str();
}

std::string optionsJsonText(const std::vector<OptionSpec>& specs, const OptionValues& values) {
  nlohmann::ordered_json out = nlohmann::ordered_json::object();
  for (const auto& [name, text] : values) {
    const OptionSpec* spec = nullptr;
    for (const OptionSpec& s : specs)
      if (s.name == name) spec = &s;
    switch (spec ? spec->kind : OptionKind::Text) {
      case OptionKind::Integer: out[name] = std::stoll(text); break;
      case OptionKind::Real: out[name] = std::stod(text); break;
      case OptionKind::Flag: out[name] = text == "true"; break;
      default: out[name] = text;
    }
  }
  return jsonText(out);
}

}  // namespace lucent
