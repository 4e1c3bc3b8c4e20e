#include <exception>
#include <iostream>

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
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::cerr << "lucent: error: " << e.what() << "\n";
    return 1;
  }
  return exitCode;
}
