#include <exception>
#include <iostream>
#include <string>

#include "cli/commands.h"
#include "lucent/core/parallel.h"
#include "lucent/core/text.h"

int main(int argc, char** argv) {
  lucent::retainFreedMemory();
  CLI::App app{"Lucent: a CPU reference renderer for global illumination"};
  app.require_subcommand(1);
  int exitCode = 0;
  lucent::cli::addCommands(app, exitCode);
  // An unknown command word, named (CLI11 would say only that a subcommand is required).
  if (argc > 1 && argv[1][0] != '-') {
    const std::string command = argv[1];
    bool known = false;
    for (const CLI::App* sub : app.get_subcommands({})) known = known || sub->get_name() == command;
    if (!known) {
      std::cerr << "lucent: error: unknown command '" << lucent::printable(command)
                << "' (commands: render, compare, methods, merge, report, check-dump, bsdf; lucent --help)\n";
      return 1;
    }
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // Help (exit code 0) goes to stdout as CLI11 writes it; an error is printed escaped, as it may
    // quote arguments. The status is Lucent's: 2 for compare's and check-dump's bad input, 1 for any other command's.
    if (e.get_exit_code() == 0) return app.exit(e);
    std::cerr << "lucent: error: " << lucent::printable(e.what()) << " (lucent --help)\n";
    return argc > 1 && (std::string(argv[1]) == "compare" || std::string(argv[1]) == "check-dump") ? 2 : 1;
  } catch (const std::bad_alloc&) {
    std::cerr << "lucent: error: out of memory: an allocation failed (lower the options that size the render, "
                 "or --memory-limit)\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "lucent: error: " << lucent::printableLines(e.what()) << "\n";
    return 1;
  }
  return exitCode;
}
