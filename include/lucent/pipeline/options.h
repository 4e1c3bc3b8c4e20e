// Options declared once. A method's options are a plain struct, whose member initializers are the
// defaults, and one OptionTable that declares each option: its name, kind, range, unit and one line
// of help, and where in the struct it lives. The command line's flags, the parsing and validation
// of values and their messages, the JSON echo and the EXR metadata, the help text and `lucent
// methods` all come from that table (src/cli/, pipeline/method.h).
#pragma once
#include <array>
#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

namespace lucent {

// A value an option does not take, or a name no option has: `option` is the option's name.
class OptionError : public std::invalid_argument {
 public:
  OptionError(std::string option, const std::string& problem)
      : std::invalid_argument(problem), option_(std::move(option)) {}
  const std::string& option() const { return option_; }

 private:
  std::string option_;
};

enum class OptionKind {
  Integer,  // whole numbers in [min, max]
  Real,     // finite numbers in [min, max]
  Flag,     // true or false
  Choice,   // one of `choices`
  Text,     // any text (a directory), or a value of its own syntax (OptionTable::value)
  Triple,   // three whole numbers XxYxZ in [min, max] each, or 0x0x0 for none
};

struct OptionSpec {
  std::string name;  // snake_case: the key in JSON; on the command line --name with '-' for '_'
  OptionKind kind = OptionKind::Integer;
  double min = 0, max = 0;           // Integer, Real, Triple
  std::vector<std::string> choices;  // Choice
  std::string unit;                  // "" for none
  std::string help;                  // one line
  std::string defaultText;           // the default as text
  bool changesImage = true;          // false: renders that differ in it alone give the same image
  std::string shortFlag;             // "-o" beside "--output", or ""
  std::string placeholder;           // what help shows for the value ("FILE"); "": from the kind
  std::string flag() const;          // "--gather-rays"
};

// Text of a number or a flag as options print and parse them (reals exactly, shortest form).
std::string optionText(double value, OptionKind kind);
// The parsers behind OptionTable: the text's value, or an OptionError naming `option`.
int64_t parseOptionInteger(const std::string& option, std::string_view text, double min, double max);
// A real option stored as a float is compared with its range as floats: the bound 0.01 is the float
// nearest 0.01, below the double 0.01, and a value written as the bound is in range.
double parseOptionReal(const std::string& option, std::string_view text, double min, double max, bool asFloat = false);
template <class T>
bool realInRange(double value, double min, double max) {
  return T(value) >= T(min) && T(value) <= T(max);  // NaN: false
}
bool parseOptionFlag(const std::string& option, std::string_view text);
std::array<uint32_t, 3> parseOptionTriple(const std::string& option, std::string_view text, double min, double max);
std::string tripleText(const std::array<uint32_t, 3>& value);
// "must be in [min, max]", with powers of two written as 2^n.
std::string rangeText(double min, double max, OptionKind kind);

// Option values by name, as text, in the order they were given.
using OptionValues = std::vector<std::pair<std::string, std::string>>;

// The values as one JSON object, by each option's kind in `specs`: numbers, true or false, and
// strings (triples and names, and a name `specs` does not declare).
std::string optionsJsonText(const std::vector<OptionSpec>& specs, const OptionValues& values);

template <class Options>
class OptionTable {
 public:
  // The defaults are the struct's member initializers, or those of `defaults` where a method's
  // defaults differ from the struct's (purcell and pmfg share one struct).
  explicit OptionTable(Options defaults = Options{}) : defaults_(std::move(defaults)) {}
  const Options& defaults() const { return defaults_; }

  // Each declaration names its field by pointer to member: &Options::field.
  template <class T>
  OptionTable& integer(std::string name, T Options::*field, double min, double max, std::string unit, std::string help) {
    static_assert(std::is_integral_v<T>);
    OptionSpec spec{std::move(name), OptionKind::Integer, min, max, {}, std::move(unit), std::move(help), {}, true, {}, {}};
    const std::string n = spec.name;
    return add(std::move(spec),
               [=](Options& o, std::string_view text) { o.*field = T(parseOptionInteger(n, text, min, max)); },
               [=](const Options& o) { return std::to_string(o.*field); },
               [=](const Options& o) {
                 const double v = double(o.*field);
                 return v >= min && v <= max ? std::string() : rangeText(min, max, OptionKind::Integer);
               });
  }
  template <class T>
  OptionTable& real(std::string name, T Options::*field, double min, double max, std::string unit, std::string help) {
    static_assert(std::is_floating_point_v<T>);
    OptionSpec spec{std::move(name), OptionKind::Real, min, max, {}, std::move(unit), std::move(help), {}, true, {}, {}};
    const std::string n = spec.name;
    constexpr bool asFloat = std::is_same_v<T, float>;
    return add(std::move(spec),
               [=](Options& o, std::string_view text) { o.*field = T(parseOptionReal(n, text, min, max, asFloat)); },
               [=](const Options& o) { return optionText(double(o.*field), OptionKind::Real); },
               [=](const Options& o) {
                 return realInRange<T>(double(o.*field), min, max) ? std::string() : rangeText(min, max, OptionKind::Real);
               });
  }
  OptionTable& flag(std::string name, bool Options::*field, std::string help) {
    OptionSpec spec{std::move(name), OptionKind::Flag, 0, 1, {}, {}, std::move(help), {}, true, {}, {}};
    const std::string n = spec.name;
    return add(std::move(spec), [=](Options& o, std::string_view text) { o.*field = parseOptionFlag(n, text); },
               [=](const Options& o) { return std::string(o.*field ? "true" : "false"); },
               [](const Options&) { return std::string(); });
  }
  template <class Enum>
  OptionTable& choice(std::string name, Enum Options::*field, std::vector<std::pair<std::string, Enum>> values,
                      std::string help) {
    OptionSpec spec{std::move(name), OptionKind::Choice, 0, 0, {}, {}, std::move(help), {}, true, {}, {}};
    for (const auto& [text, value] : values) spec.choices.push_back(text);
    const std::string n = spec.name;
    const std::vector<std::string> choices = spec.choices;
    return add(
        std::move(spec),
        [=](Options& o, std::string_view text) {
          for (const auto& [t, value] : values)
            if (t == text) {
              o.*field = value;
              return;
            }
          // Appended piece by piece: "'" + a temporary makes GCC 12 warn falsely (-Wrestrict).
          std::string message = "'";
          message.append(text).append("' is not one of ");
          for (size_t k = 0; k < choices.size(); ++k) message.append(k ? ", " : "").append(choices[k]);
          throw OptionError(n, message);
        },
        [=](const Options& o) {
          for (const auto& [t, value] : values)
            if (value == o.*field) return t;
          return std::string("?");
        },
        [=](const Options& o) {
          for (const auto& [t, value] : values)
            if (value == o.*field) return std::string();
          return std::string("has a value that is not one of its choices");
        });
  }
  OptionTable& text(std::string name, std::string Options::*field, std::string unit, std::string help) {
    OptionSpec spec{std::move(name), OptionKind::Text, 0, 0, {}, std::move(unit), std::move(help), {}, true, {}, {}};
    return add(std::move(spec), [=](Options& o, std::string_view text) { o.*field = std::string(text); },
               [=](const Options& o) { return o.*field; }, [](const Options&) { return std::string(); });
  }
  OptionTable& triple(std::string name, std::array<uint32_t, 3> Options::*field, double min, double max,
                      std::string unit, std::string help) {
    OptionSpec spec{std::move(name), OptionKind::Triple, min, max, {}, std::move(unit), std::move(help), {}, true, {}, {}};
    const std::string n = spec.name;
    return add(std::move(spec), [=](Options& o, std::string_view text) { o.*field = parseOptionTriple(n, text, min, max); },
               [=](const Options& o) { return tripleText(o.*field); },
               [=](const Options& o) {
                 const std::array<uint32_t, 3>& v = o.*field;
                 if (v[0] == 0 && v[1] == 0 && v[2] == 0) return std::string();
                 for (uint32_t c : v)
                   if (c < min || c > max) return "each of three " + rangeText(min, max, OptionKind::Integer) + ", or 0x0x0";
                 return std::string();
               });
  }
  // Every option and rule of `shared`, whose struct is the member `part` of these options (the
  // options several methods share, render_options.h); the defaults are these options'.
  template <class Part>
  OptionTable& include(Part Options::*part, const OptionTable<Part>& shared) {
    for (size_t i = 0; i < shared.specs_.size(); ++i) {
      const typename OptionTable<Part>::Entry e = shared.entries_[i];
      add(shared.specs_[i], [=](Options& o, std::string_view text) { e.parse(o.*part, text); },
          [=](const Options& o) { return e.format(o.*part); }, [=](const Options& o) { return e.check(o.*part); });
    }
    for (const auto& r : shared.rules_) {
      auto check = r.check;
      rule(r.option, [=](const Options& o) { return check(o.*part); });
    }
    return *this;
  }
  // A value of a syntax of its own ("X0,Y0,X1,Y1"), read by `parse` (which throws
  // std::invalid_argument with the whole message, naming the flag) and written by `format`.
  template <class T>
  OptionTable& value(std::string name, T Options::*field, std::string placeholder, std::function<T(const std::string&)> parse,
                     std::function<std::string(const T&)> format, std::string help) {
    OptionSpec spec{std::move(name), OptionKind::Text, 0, 0, {}, {}, std::move(help), {}, true, {}, {}};
    spec.placeholder = std::move(placeholder);
    return add(std::move(spec), [=](Options& o, std::string_view text) { o.*field = parse(std::string(text)); },
               [=](const Options& o) { return format(o.*field); }, [](const Options&) { return std::string(); });
  }
  // What help shows for an option's value, and a short flag beside its long one.
  OptionTable& placeholder(std::string_view name, std::string text) {
    spec(name).placeholder = std::move(text);
    return *this;
  }
  OptionTable& shortFlag(std::string_view name, std::string flag) {
    spec(name).shortFlag = std::move(flag);
    return *this;
  }
  // Marks an option whose value never changes the image (a tile size, a dump directory): parts and
  // checkpoints of renders that differ in it alone belong to the same render.
  OptionTable& imageNeutral(std::string_view name) {
    spec(name).changesImage = false;
    return *this;
  }
  // A condition beyond the option's range (a power of two, a pairing with another option):
  // check(options) returns why the options break it, or "".
  OptionTable& rule(std::string option, std::function<std::string(const Options&)> check) {
    rules_.push_back({std::move(option), std::move(check)});
    return *this;
  }

  // Option `option`'s value where the options given leave it out and `when` holds of them: `text`
  // instead of its declared default (an error target's spp, the most a pixel takes: high, for the
  // target asks for as many samples as it needs).
  OptionTable& defaultWhen(std::string option, std::function<bool(const Options&)> when, std::string text) {
    if (!has(option)) throw std::logic_error("option '" + option + "' is not declared");
    conditionalDefaults_.push_back({std::move(option), std::move(when), std::move(text)});
    return *this;
  }
  // Sets the conditional defaults (defaultWhen) of the options that `given` leaves out.
  void setConditionalDefaults(Options& options, const OptionValues& given) const {
    for (const ConditionalDefault& d : conditionalDefaults_) {
      bool named = false;
      for (const auto& [name, text] : given) named = named || name == d.option;
      if (!named && d.when(options)) set(options, d.option, d.text);
    }
  }

  const std::vector<OptionSpec>& specs() const { return specs_; }
  bool has(std::string_view name) const { return find(name) != nullptr; }

  // Sets one option from text; throws OptionError for an unknown name or a bad value.
  void set(Options& options, std::string_view name, std::string_view text) const {
    const Entry* e = find(name);
    if (!e) throw OptionError(std::string(name), "no such option");
    e->parse(options, text);
  }
  // Every option's value as text, in declaration order.
  OptionValues values(const Options& options) const {
    OptionValues out;
    for (size_t i = 0; i < entries_.size(); ++i) out.emplace_back(specs_[i].name, entries_[i].format(options));
    return out;
  }
  // Every range and rule, in declaration order: the first broken one throws OptionError.
  void validate(const Options& options) const {
    for (size_t i = 0; i < entries_.size(); ++i)
      if (const std::string why = entries_[i].check(options); !why.empty()) throw OptionError(specs_[i].name, why);
    for (const Rule& r : rules_)
      if (const std::string why = r.check(options); !why.empty()) throw OptionError(r.option, why);
  }

 private:
  template <class>
  friend class OptionTable;
  struct Entry {
    std::function<void(Options&, std::string_view)> parse;
    std::function<std::string(const Options&)> format;
    std::function<std::string(const Options&)> check;
  };
  struct Rule {
    std::string option;
    std::function<std::string(const Options&)> check;
  };
  struct ConditionalDefault {
    std::string option;
    std::function<bool(const Options&)> when;
    std::string text;
  };
  OptionTable& add(OptionSpec spec, std::function<void(Options&, std::string_view)> parse,
                   std::function<std::string(const Options&)> format, std::function<std::string(const Options&)> check) {
    if (has(spec.name)) throw std::logic_error("option '" + spec.name + "' declared twice");
    spec.defaultText = format(defaults_);
    specs_.push_back(std::move(spec));
    entries_.push_back({std::move(parse), std::move(format), std::move(check)});
    return *this;
  }
  OptionSpec& spec(std::string_view name) {
    for (OptionSpec& s : specs_)
      if (s.name == name) return s;
    throw std::logic_error("no option '" + std::string(name) + "' to mark");
  }
  const Entry* find(std::string_view name) const {
    for (size_t i = 0; i < specs_.size(); ++i)
      if (specs_[i].name == name) return &entries_[i];
    return nullptr;
  }
  Options defaults_;
  std::vector<OptionSpec> specs_;
  std::vector<Entry> entries_;
  std::vector<Rule> rules_;
  std::vector<ConditionalDefault> conditionalDefaults_;
};

}  // namespace lucent
