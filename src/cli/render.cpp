#include "cli/commands.h"
namespace lucent::cli {
void addRenderCommand(CLI::App& app, int& exitCode) {}
}
