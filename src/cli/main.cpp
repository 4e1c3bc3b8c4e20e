#include <exception>
#include <iostream>
#include <string>

#include "cli/commands.h"
#include "lucent/core/parallel.h"

int main(int argc, char** argv) {
  lucent::retainFreedMemory();
  CLI::App app{"Lucent: a CPU reference renderer for global illumination"};
  app.require_subcommand(1);
  int exitCode = 0;
  lucent::cli::addRenderCommand(app, exitCode);
  lucent::cli::addCompareCommand(app, exitCode);
  lucent::cli::addMethodsCommand(app, exitCode);
  lucent::cli::addMergeCommand(app, exitCode);
  lucent::cli::addReportCommand(app, exitCode);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // CLI11 prints the message (or the help); the status is Lucent's: 0 for help, 2 for a
    // compare's bad input, 1 for any other command's.
    const int status = app.exit(e);
    if (status == 0) return 0;
    return argc > 1 && std::string(argv[1]) == "compare" ? 2 : 1;
  } catch (const std::exception& e) {
    std::cerr << "lucent: error: " << e.what() << "\n";
    return 1;
  }
  return exitCode;
}
