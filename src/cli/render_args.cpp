#include "cli/render_args.h"

#include <sstream>
#include <stdexcept>

#include "cli/method_options.h"
#include "lucent/core/memory.h"
#include "lucent/core/parallel.h"
#include "lucent/methods/methods.h"

namespace lucent::cli {

namespace {

// The value `parse` reads from a render flag's text; its OptionError named after the flag.
template <class Parse>
auto flagged(Parse parse) {
  try {
    return parse();
  } catch (const OptionError& e) {
    throw std::invalid_argument("--" + e.option() + ": " + e.what());
  }
}

// "X0,Y0,X1,Y1": integers with X0 < X1, Y0 < Y1 (inside the image: checked once its size is known).
PixelRect parseCrop(const std::string& text) {
  PixelRect r;
  char c1 = 0, c2 = 0, c3 = 0, rest = 0;
  std::istringstream in(text);
  if (!(in >> r.x0 >> c1 >> r.y0 >> c2 >> r.x1 >> c3 >> r.y1) || c1 != ',' || c2 != ',' || c3 != ',' || (in >> rest) ||
      r.x0 < 0 || r.y0 < 0 || r.x0 >= r.x1 || r.y0 >= r.y1)
    throw std::invalid_argument("--crop '" + text + "': expected X0,Y0,X1,Y1 with 0 <= X0 < X1 and 0 <= Y0 < Y1");
  return r;
}

// "FIRST:COUNT", FIRST >= 0, COUNT >= 1 (inside the samples per pixel: checked by the method).
std::pair<int, int> parseSamples(const std::string& text) {
  const size_t colon = text.find(':');
  if (colon == std::string::npos) throw std::invalid_argument("--samples '" + text + "': expected FIRST:COUNT");
  const int first = int(flagged([&] { return parseOptionInteger("samples", text.substr(0, colon), 0, 1 << 24); }));
  const int count = int(flagged([&] { return parseOptionInteger("samples", text.substr(colon + 1), 1, 1 << 24); }));
  return {first, count};
}

// "WIDTHxHEIGHT", each in [1, kMaxImageSide], at most kMaxImagePixels in all.
std::pair<int, int> parseResolution(const std::string& text) {
  int w = 0, h = 0;
  char x = 0, rest = 0;
  std::istringstream in(text);
  if (!(in >> w >> x >> h) || x != 'x' || (in >> rest) || w < 1 || h < 1 || w > kMaxImageSide || h > kMaxImageSide)
    throw std::invalid_argument("--resolution '" + text + "': expected WIDTHxHEIGHT, e.g. 512x512");
  if (uint64_t(w) * h > kMaxImagePixels) throw std::invalid_argument("--resolution '" + text + "': more than 2^26 pixels");
  return {w, h};
}

// "512M", "8G" or bytes: more than 0, within what the process may address.
uint64_t parseMemoryLimit(const std::string& text) {
  uint64_t limit = 0;
  try {
    limit = parseMemorySize(text);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("--memory-limit " + std::string(e.what()));
  }
  if (limit == 0) throw std::invalid_argument("--memory-limit must be more than 0 bytes");
  if (limit > addressSpaceLimit())
    throw std::invalid_argument("--memory-limit " + text + ": more than this process may address (ulimit -v: " +
                                memoryText(addressSpaceLimit()) + ")");
  return limit;
}

std::string pairText(const std::pair<int, int>& p, char separator) {
  return p.second == 0 ? std::string() : std::to_string(p.first) + separator + std::to_string(p.second);
}

}  // namespace

const OptionTable<RenderArgs>& renderFlags() {
  static const OptionTable<RenderArgs> table = [] {
    using A = RenderArgs;
    OptionTable<A> t;
    t.text("method", &A::method, "", "rendering method (lucent methods lists them); none: the scene's render block's, else pt");
    t.placeholder("method", "NAME");
    t.text("output", &A::output, "", "output EXR file (required)");
    t.placeholder("output", "FILE").shortFlag("output", "-o");
    t.text("png", &A::png, "", "also write an sRGB PNG");
    t.placeholder("png", "FILE");
    t.integer("threads", &A::threads, 0, kMaxThreads, "threads", "worker threads (0: all cores)");
    t.value<std::pair<int, int>>("resolution", &A::resolution, "WxH", parseResolution,
                                 [](const std::pair<int, int>& r) { return pairText(r, 'x'); },
                                 "override the camera's resolution");
    t.value<PixelRect>("crop", &A::crop, "X0,Y0,X1,Y1", parseCrop,
                       [](const PixelRect& r) {
                         return r.empty() ? std::string()
                                          : std::to_string(r.x0) + "," + std::to_string(r.y0) + "," +
                                                std::to_string(r.x1) + "," + std::to_string(r.y1);
                       },
                       "render only the pixels [X0, X1) x [Y0, Y1): a part of a split render, with OUT.film for "
                       "lucent merge");
    t.value<std::pair<int, int>>("samples", &A::samples, "FIRST:COUNT", parseSamples,
                                 [](const std::pair<int, int>& s) { return pairText(s, ':'); },
                                 "take only the camera samples FIRST to FIRST+COUNT-1 of each pixel: a part of a "
                                 "split render, with OUT.film for lucent merge");
    t.text("part", &A::part, "",
           "the K-th of N parts (K from 0) of the image's rows or of each pixel's samples, as --crop or --samples "
           "would give it (for job arrays)");
    t.placeholder("part", "rows|samples:K/N");
    t.real("checkpoint", &A::checkpointSeconds, 1e-3, 1e9, "s",
           "every SECONDS, write the render's state to OUT.film (also on SIGINT and SIGTERM)");
    t.placeholder("checkpoint", "SECONDS");
    t.flag("resume", &A::resume, "continue from OUT.film, left by a checkpoint or a stop, if there is one");
    t.value<uint64_t>("memory_limit", &A::memoryLimit, "SIZE", parseMemoryLimit,
                      [](const uint64_t& bytes) { return bytes == 0 ? std::string() : memoryText(bytes); },
                      "the most memory the render may hold, as 512M, 8G or bytes; one that would need more stops "
                      "at once, naming the option to lower (none: the available memory)");
    t.flag("robust", &A::robust, "Embree's robust traversal (watertight at edges)");
    t.text("isa", &A::isa, "",
           "run as a CPU of sse4.2, avx, avx2 or avx512 would: Embree's kernels and the lane loops (none: this "
           "CPU's best)");
    t.placeholder("isa", "ISA");
    t.flag("strict", &A::strict,
           "refuse a scene whose files hold what the render would leave out (a glTF material's occlusion texture "
           "or volume: the JSON line's \"ignored\")");
    t.choice<bool>("gltf_masking", &A::gltfHeightCorrelated, {{"height-correlated", true}, {"separable", false}},
                   "Smith masking-shadowing of glTF materials: the height-correlated form of Appendix B and most GPU "
                   "engines, or the separable one the appendix gave before its 2026 revision (a scene file's glTF "
                   "entry may set its own)");
    t.choice<bool>("gltf_normal_maps", &A::gltfBendNormalMaps, {{"bend", true}, {"as-given", false}},
                   "glTF normal maps: bent per viewing direction so that mirror reflections stay above the surface, "
                   "as production renderers do, or as the texture gives them (reflections below the surface are "
                   "lost: dark rims) (a scene file's glTF entry may set its own)");
    t.real("lumens_per_watt", &A::lumensPerWatt, 1e-6, 1e6, "lm/W",
           "glTF lights' photometric intensities (cd, lx) to watts (a scene file's glTF entry may set its own)");
    t.text("gltf_camera", &A::gltfCamera, "",
           "render a glTF file from the camera of this name (its node's or its own; none: the first)");
    t.placeholder("gltf_camera", "NAME");
    t.flag("quiet", &A::quiet, "no progress bar or warnings");
    t.shortFlag("quiet", "-q");
    t.flag("log_stages", &A::logStages, "print each stage's name on stderr as it starts, with the seconds since the start");
    t.flag("help", &A::help, "this help, with the options of --method NAME");
    t.shortFlag("help", "-h");
    return t;
  }();
  return table;
}

namespace {

// The render flag whose long or short form is `key`, or nullptr.
const OptionSpec* renderFlag(const std::string& key) {
  for (const OptionSpec& spec : renderFlags().specs())
    if (key == spec.flag() || key == spec.shortFlag) return &spec;
  return nullptr;
}

}  // namespace

RenderArgs parseRenderArgs(const std::vector<std::string>& args) {
  RenderArgs a;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& arg = args[i];
    const size_t eq = arg.find('=');
    const bool inlineValue = arg.rfind("--", 0) == 0 && eq != std::string::npos;
    const std::string key = inlineValue ? arg.substr(0, eq) : arg;
    auto value = [&]() -> std::string {
      if (inlineValue) return arg.substr(eq + 1);
      if (i + 1 >= args.size()) throw std::invalid_argument(key + " needs a value");
      return args[++i];
    };
    if (const OptionSpec* flag = renderFlag(key)) {
      const bool takesValue = flag->kind != OptionKind::Flag;
      if (!takesValue && inlineValue) throw std::invalid_argument(key + " takes no value");
      try {
        renderFlags().set(a, flag->name, takesValue ? value() : "true");
      } catch (const OptionError& e) {
        throw std::invalid_argument(flag->flag() + ": " + e.what());
      }
    } else if (key.rfind("--", 0) == 0) {
      a.methodOptions.push_back(methodOptionArg(key, inlineValue ? std::optional(arg.substr(eq + 1)) : std::nullopt,
                                                i + 1 < args.size() ? std::optional(args[i + 1]) : std::nullopt,
                                                [&] { return value(); }));
    } else if (key.rfind("-", 0) == 0 && key.size() > 1) {
      throw std::invalid_argument("unknown option " + key);
    } else if (a.scene.empty()) {
      a.scene = arg;
    } else {
      throw std::invalid_argument("one scene file only: '" + a.scene + "' and '" + arg + "'");
    }
  }
  return a;
}

}  // namespace lucent::cli
