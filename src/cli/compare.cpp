#include "cli/commands.h"
namespace lucent::cli {
void addCompareCommand(CLI::App& app, int& exitCode) {}
}
