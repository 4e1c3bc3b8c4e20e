// Options declared once (pipeline/options.h): the table's parsing, ranges and rules, and every
// method's declarations carried through to the command line's flags, help, validation, JSON echo
// and EXR metadata, `lucent methods` and scene files' render blocks. The checks walk the
// declarations; none lists an option by hand, except to test a render block.
#include <catch2/catch.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>

#include "lucent/image/image.h"
#include "lucent/methods/methods.h"
#include "test_scenes.h"
#include "test_support.h"

using namespace lucent;

namespace {

struct Example {
  int count = 3;
  float scale = 0.5f;
  bool on = true;
  enum class Mode { A, B } mode = Mode::B;
  std::string path;
  std::array<uint32_t, 3> cells{0, 0, 0};
};

OptionTable<Example> exampleTable() {
  OptionTable<Example> t;
  t.integer("count", &Example::count, 1, 1 << 20, "things", "how many");
  t.real("scale", &Example::scale, 0, 10, "", "how large");
  t.flag("on", &Example::on, "whether");
  t.choice("mode", &Example::mode,
           std::vector<std::pair<std::string, Example::Mode>>{{"a", Example::Mode::A}, {"b", Example::Mode::B}}, "which");
  t.text("path", &Example::path, "", "where");
  t.triple("cells", &Example::cells, 1, 100, "cells", "grid");
  t.rule("count", [](const Example& e) { return e.count % 2 == 1 ? "" : "must be odd"; });
  return t;
}

std::string problem(const OptionTable<Example>& t, const std::string& name, const std::string& text) {
  Example e;
  try {
    t.set(e, name, text);
    t.validate(e);
  } catch (const OptionError& error) {
    CHECK(error.option() == name);
    return error.what();
  }
  return "";
}

using test::quoted;
using test::runLucent;
const std::string kScene = LUCENT_SOURCE_DIR "/scenes/cornell-box.json";

}  // namespace

TEST_CASE("An option table parses, prints, checks ranges and rules, and names the option", "[options]") {
  const OptionTable<Example> t = exampleTable();
  REQUIRE(t.specs().size() == 6);
  CHECK(t.specs()[0].flag() == "--count");
  // The defaults are the struct's, as text.
  const OptionValues defaults = t.values(Example{});
  CHECK(defaults == OptionValues{{"count", "3"}, {"scale", "0.5"}, {"on", "true"}, {"mode", "b"}, {"path", ""}, {"cells", "auto"}});
  for (size_t i = 0; i < defaults.size(); ++i) CHECK(t.specs()[i].defaultText == defaults[i].second);
  // Values round-trip through their text.
  Example e;
  for (const auto& [name, text] : OptionValues{{"count", "7"}, {"scale", "0.1"}, {"on", "false"}, {"mode", "a"},
                                               {"path", "/tmp/x y"}, {"cells", "25x1x50"}})
    t.set(e, name, text);
  CHECK(t.values(e) == OptionValues{{"count", "7"}, {"scale", "0.1"}, {"on", "false"}, {"mode", "a"}, {"path", "/tmp/x y"},
                                    {"cells", "25x1x50"}});
  // Refusals, each naming the problem.
  CHECK(problem(t, "count", "0") == "'0' must be in [1, 2^20]");
  CHECK(problem(t, "count", "2") == "must be odd");
  CHECK(problem(t, "count", "1.5") == "'1.5' is not a whole number");
  CHECK(problem(t, "count", "99999999999999999999") == "'99999999999999999999' must be in [1, 2^20]");
  CHECK(problem(t, "scale", "nan") == "'nan' is not a finite number");
  CHECK(problem(t, "scale", "11") == "'11' must be in [0, 10]");
  CHECK(problem(t, "on", "maybe") == "'maybe' is not true or false");
  CHECK(problem(t, "mode", "c") == "'c' is not one of a, b");
  CHECK(problem(t, "cells", "25x25") == "'25x25': expected three whole numbers XxYxZ, e.g. 25x25x50");
  CHECK(problem(t, "cells", "0x1x1") == "'0x1x1': each count must be in [1, 100]");
  CHECK(problem(t, "nonsense", "1") == "no such option");
  // Values set in code are checked by validate.
  Example wrong;
  wrong.scale = -1;
  CHECK_THROWS_WITH(t.validate(wrong), "must be in [0, 10]");
  OptionTable<Example> twice = exampleTable();
  CHECK_THROWS_AS(twice.flag("on", &Example::on, "again"), std::logic_error);
}

TEST_CASE("Every method takes each option's bounds exactly as its range is written", "[options]") {
  // A float field's bound written as 0.01 was compared as a double with the float nearest 0.01,
  // which lies below it, and refused.
  struct Real {
    float value = 1;
  };
  OptionTable<Real> table;
  table.real("value", &Real::value, 0.01, 0.3, "", "");
  for (const char* text : {"0.01", "0.3"}) {
    Real r;
    CHECK_NOTHROW(table.set(r, "value", text));
    CHECK_NOTHROW(table.validate(r));
  }
  CHECK_THROWS(table.set(*std::make_unique<Real>(), "value", "0.0099999"));
  for (const Method* method : renderingMethods())
    for (const OptionSpec& spec : method->options()) {
      if (spec.kind != OptionKind::Integer && spec.kind != OptionKind::Real) continue;
      for (const double bound : {spec.min, spec.max}) {
        const std::string text = optionText(bound, spec.kind);
        CAPTURE(method->name(), spec.name, text);
        try {
          method->resolve({{spec.name, text}});
        } catch (const OptionError& e) {
          // A rule pairing it with another option may refuse it; its range may not.
          CHECK_THAT(e.what(), !Catch::Contains("must be in") && !Catch::Contains("must be finite"));
        }
      }
    }
}

TEST_CASE("Every method's options reach the command line, the help, the JSON line and the EXR", "[options][cli]") {
  test::TempDir dir("options");
  for (const Method* method : renderingMethods()) {
    CAPTURE(method->name());
    // Every option given at its default: the render runs, and echoes each value where it belongs.
    std::string args;
    for (const OptionSpec& spec : method->options()) {
      // Appended piece by piece (here and below): " " + a temporary makes GCC 12 warn falsely (-Wrestrict).
      args.append(" ").append(spec.flag());
      if (spec.kind == OptionKind::Flag) args.append("=").append(spec.defaultText);
      else if (spec.kind == OptionKind::Text) args.append(" ").append(quoted(dir.path.string()));
      else args.append(" ").append(spec.defaultText);
    }
    const std::string exr = dir / (method->name() + ".exr");
    // Light settings for time, given after the defaults (the last value of an option counts).
    std::string light = " --spp 1";
    for (const OptionSpec& spec : method->options())
      if (spec.name == "photons" || spec.name == "caustic_photons") light.append(" ").append(spec.flag()).append(" 1000");
      else if (spec.name == "gather_rays" || spec.name == "light_samples") light.append(" ").append(spec.flag()).append(" 1");
      else if (spec.name == "points" && spec.defaultText != "0") light.append(" ").append(spec.flag()).append(" 4096");
    // The environment-lighting method needs a scene without emitting triangles.
    const std::string scene = method->name() == "envpbgi" ? quoted(LUCENT_SOURCE_DIR "/scenes/primitives.json") : kScene;
    const test::CliRun r = runLucent("render " + scene + " --method " + method->name() + args + light +
                                     " --resolution 8x8 --quiet -o " + quoted(exr));
    INFO(r.output);
    REQUIRE(r.status == 0);
    const auto summary = nlohmann::json::parse(r.output);
    const auto& options = summary["options"];
    REQUIRE(options.size() == method->options().size());
    for (const OptionSpec& spec : method->options()) {
      CAPTURE(spec.name);
      REQUIRE(options.contains(spec.name));
      if (spec.name == "dump" || spec.name == "spp" || light.find(spec.flag() + " ") != std::string::npos) continue;
      switch (spec.kind) {
        case OptionKind::Integer: CHECK(std::to_string(options[spec.name].get<int64_t>()) == spec.defaultText); break;
        case OptionKind::Real: CHECK(float(options[spec.name].get<double>()) == std::stof(spec.defaultText)); break;
        case OptionKind::Flag: CHECK((options[spec.name].get<bool>() ? "true" : "false") == spec.defaultText); break;
        default: CHECK(options[spec.name].get<std::string>() == spec.defaultText);
      }
    }
    ImageMetadata meta;
    readImage(exr, &meta);
    std::string metaOptions;
    for (const auto& [key, value] : meta)
      if (key == "lucent:options") metaOptions = value;
    CHECK(nlohmann::json::parse(metaOptions) == options);

    // The help shows this method's options, each with its help and default, and no other method's.
    const test::CliRun help = runLucent("render --method " + method->name() + " --help");
    REQUIRE(help.status == 0);
    for (const OptionSpec& spec : method->options()) {
      CHECK_THAT(help.output, Catch::Contains(spec.flag()) && Catch::Contains(spec.help));
      CHECK_THAT(help.output, Catch::Contains("default " + (spec.defaultText.empty() ? "none" : spec.defaultText)));
    }
    for (const Method* other : renderingMethods())
      for (const OptionSpec& spec : other->options())
        if (std::none_of(method->options().begin(), method->options().end(),
                         [&](const OptionSpec& own) { return own.name == spec.name; }))
          CHECK_THAT(help.output, !Catch::Contains("  " + spec.flag() + " ") && !Catch::Contains("  " + spec.flag() + "\n"));

    // A value outside an option's range is refused by the command line, naming the option, with no output.
    for (const OptionSpec& spec : method->options()) {
      if (spec.kind != OptionKind::Integer && spec.kind != OptionKind::Real) continue;
      CAPTURE(spec.name);
      const std::string out = dir / "refused.exr";
      const test::CliRun bad = runLucent("render " + kScene + " --method " + method->name() + " " + spec.flag() + " " +
                                         optionText(spec.max * 2 + 1, spec.kind) + " --resolution 4x4 --quiet -o " + quoted(out));
      CHECK(bad.status == 1);
      CHECK_THAT(bad.output, Catch::Contains("lucent: error: " + spec.flag() + ": "));
      CHECK_FALSE(std::filesystem::exists(out));
    }
  }
}

TEST_CASE("An option of another method is refused, naming the method it belongs to", "[options][cli]") {
  test::TempDir dir("options");
  int refused = 0;
  for (const Method* method : renderingMethods())
    for (const Method* other : renderingMethods())
      for (const OptionSpec& spec : other->options()) {
        if (std::any_of(method->options().begin(), method->options().end(), [&](const OptionSpec& s) { return s.name == spec.name; }))
          continue;
        const std::string value = spec.kind == OptionKind::Flag ? "" : " " + (spec.defaultText.empty() ? "x" : spec.defaultText);
        const test::CliRun r = runLucent("render " + kScene + " --method " + method->name() + " " + spec.flag() + value +
                                         " --resolution 4x4 --quiet -o " + quoted(dir / "x.exr"));
        CAPTURE(method->name(), spec.name, r.output);
        CHECK(r.status == 1);
        CHECK_THAT(r.output, Catch::Contains(spec.flag() + ": an option of --method ") &&
                                 Catch::Contains(", not of --method " + method->name()));
        ++refused;
        break;  // one per pair of methods is enough
      }
  CHECK(refused >= 6);
}

TEST_CASE("lucent methods lists every method with its declared options", "[options][cli]") {
  const test::CliRun r = runLucent("methods --json");
  REQUIRE(r.status == 0);
  const auto listed = nlohmann::json::parse(r.output);
  REQUIRE(listed.size() == renderingMethods().size());
  for (size_t m = 0; m < listed.size(); ++m) {
    const Method& method = *renderingMethods()[m];
    CHECK(listed[m]["name"] == method.name());
    REQUIRE(listed[m]["options"].size() == method.options().size());
    for (size_t i = 0; i < method.options().size(); ++i) {
      CHECK(listed[m]["options"][i]["flag"] == method.options()[i].flag());
      CHECK(listed[m]["options"][i]["help"] == method.options()[i].help);
    }
  }
  const test::CliRun text = runLucent("methods pmfg");
  CHECK(text.status == 0);
  CHECK_THAT(text.output, Catch::Contains("--gather-rays N") && Catch::Contains("default 4096"));
  CHECK(runLucent("methods nonsense").status != 0);
}

TEST_CASE("A scene file's render block chooses the method and its options, the command line overrides them",
          "[options][cli]") {
  test::TempDir dir("options");
  const nlohmann::json original = nlohmann::json::parse(std::ifstream(kScene));
  auto writeScene = [&](const nlohmann::json& render) {
    nlohmann::json scene = original;
    scene["meshes"][0]["obj"] = LUCENT_SOURCE_DIR "/scenes/cornell-box/cornell_box.obj";
    scene["render"] = render;
    std::ofstream(dir / "scene.json") << scene.dump();
    return dir / "scene.json";
  };
  const std::string scene = writeScene({{"method", "pmfg"}, {"gather_rays", 2}, {"photons", 3000}, {"layers", true},
                                        {"map", "sort"}, {"grid_resolution", "8x8x8"}});
  auto render = [&](const std::string& extra) {
    return runLucent("render " + quoted(scene) + " --resolution 8x8 --quiet -o " + quoted(dir / "out.exr") + extra);
  };
  {
    const test::CliRun r = render("");
    INFO(r.output);
    REQUIRE(r.status == 0);
    const auto summary = nlohmann::json::parse(r.output);
    CHECK(summary["method"] == "pmfg");
    CHECK(summary["options"]["gather_rays"] == 2);
    CHECK(summary["options"]["photons"] == 3000);
    CHECK(summary["options"]["layers"] == true);
    CHECK(summary["options"]["map"] == "sort");
    CHECK(summary["options"]["grid_resolution"] == "8x8x8");
  }
  {
    const test::CliRun r = render(" --gather-rays 3 --no-layers");
    INFO(r.output);
    REQUIRE(r.status == 0);
    const auto summary = nlohmann::json::parse(r.output);
    CHECK(summary["options"]["gather_rays"] == 3);
    CHECK(summary["options"]["photons"] == 3000);
    CHECK(summary["options"]["layers"] == false);
  }
  {
    // Another method on the command line: the block's options are pmfg's, and do not apply.
    const test::CliRun r = render(" --method pt --spp 1");
    INFO(r.output);
    REQUIRE(r.status == 0);
    CHECK(nlohmann::json::parse(r.output)["method"] == "pt");
  }
  for (const auto& [block, message] : std::vector<std::pair<nlohmann::json, std::string>>{
           {{{"method", "pmfg"}, {"bogus", 1}}, "render.bogus: not an option of --method pmfg"},
           {{{"method", "pmfg"}, {"gather_rays", -1}}, "render.gather_rays: '-1' must be in [0, 2^20]"},
           {{{"method", "micro"}, {"gather_rays", 4}}, "render.gather_rays: an option of --method pmfg, not of --method micro"},
           {{{"method", "nonsense"}}, "unknown method 'nonsense'"},
           {{{"method", "pmfg"}, {"gather_rays", {1, 2}}}, "render.gather_rays: expected a number"}}) {
    writeScene(block);
    const test::CliRun r = render("");
    CAPTURE(block.dump(), r.output);
    CHECK(r.status == 1);
    CHECK_THAT(r.output, Catch::Contains(message));
  }
}

TEST_CASE("Options are resolved once into the method's typed struct, and only that method renders them",
          "[options]") {
  // The values given by name become the typed options (spp read back from them, not from text),
  // and their echo is those options formatted, in declaration order.
  const std::unique_ptr<MethodOptions> micro = renderingMethod("micro").resolve({{"spp", "3"}, {"seed", "7"}});
  CHECK(micro->common().spp == 3);
  CHECK(micro->common().seed == 7);
  const OptionValues values = micro->values();
  REQUIRE(values.size() == renderingMethod("micro").options().size());
  CHECK(std::find(values.begin(), values.end(), std::pair<std::string, std::string>("spp", "3")) != values.end());
  const Scene scene = test::furnaceBox(Rgb(0.5f), Rgb(1.0f), test::testCamera({0, 0, 0}, {0, 0, -1}, 4, 4));
  const Visibility vis(scene);
  REQUIRE_THROWS_WITH(renderingMethod("pt").render(scene, vis, *micro),
                      Catch::Contains("--method pt was given another method's options"));
  // purcell and pmfg share one options struct; each still takes only its own.
  REQUIRE_THROWS_WITH(renderingMethod("pmfg").render(scene, vis, *renderingMethod("purcell").resolve({})),
                      Catch::Contains("another method's options"));
}
