// libFuzzer target for the command line (src/cli/): one input is the arguments after `lucent`,
// separated by NUL bytes (at most 64). They are parsed as the lucent program parses them, every
// command registered, up to where each command's work would start: CLI11's parsing and checks for compare,
// merge, report, methods and check-dump; for render, its own flags (parseRenderArgs) and the chosen
// method's options and the part resolved and checked by RenderSession
// (render/render_session.h) against a scene without a render block, outputs left out (they would
// be created to check them). Every rejection must be a CLI::ParseError, std::invalid_argument or std::runtime_error;
// anything else, a crash, a sanitizer report, a hang or a large allocation is a defect. Seeds:
// scripts/fuzz-corpus.py command_line.
#include <CLI/CLI.hpp>

#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "cli/commands.h"
#include "cli/render_args.h"
#include "lucent/methods/methods.h"
#include "lucent/render/render_session.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string_view input(reinterpret_cast<const char*>(data), size);
  std::vector<std::string> args = {"lucent"};
  while (!input.empty() && args.size() <= 64) {
    const size_t end = std::min(input.find('\0'), input.size());
    args.emplace_back(input.substr(0, end));
    input.remove_prefix(std::min(input.size(), end + 1));
  }
  CLI::App app{"lucent"};
  app.require_subcommand(1);
  int exitCode = 0;
  lucent::cli::addCommands(app, exitCode);
  // Once everything is parsed and checked, before any command's callback runs its work (the app's
  // own parse-complete callback runs first; each command's state lives in its callback, so the
  // callbacks stay as they are).
  struct Parsed {};
  app.parse_complete_callback([] { throw Parsed(); });
  std::vector<const char*> argv;
  for (const std::string& a : args) argv.push_back(a.c_str());
  try {
    try {
      app.parse(int(argv.size()), argv.data());
      return 0;  // no command: --help (CLI::CallForHelp) or nothing
    } catch (const Parsed&) {
    }
    CLI::App* render = app.get_subcommand("render");
    if (render->parsed()) {
      const lucent::cli::RenderArgs parsed = lucent::cli::parseRenderArgs(render->remaining());
      lucent::OpenScene scene(lucent::Scene{}, "fuzz.json", {});
      lucent::RenderRequest request;
      request.method = parsed.method;
      request.options = parsed.methodOptions;
      request.crop = parsed.crop;
      request.samples = parsed.samples;
      request.part = parsed.part;
      request.checkpointSeconds = parsed.checkpointSeconds;
      request.threads = parsed.threads;
      (void)lucent::RenderSession(scene, request);
    }
  } catch (const CLI::ParseError&) {
  } catch (const std::invalid_argument&) {
  } catch (const std::runtime_error&) {
  }
  return 0;
}
