// Subcommands of the lucent executable. Each registers itself on the app; its callback runs the
// command and stores the process exit status in `exitCode`.
#pragma once
#include <CLI/CLI.hpp>

namespace lucent::cli {
void addRenderCommand(CLI::App& app, int& exitCode);
void addCompareCommand(CLI::App& app, int& exitCode);
void addMethodsCommand(CLI::App& app, int& exitCode);
void addMergeCommand(CLI::App& app, int& exitCode);
void addReportCommand(CLI::App& app, int& exitCode);
void addCheckDumpCommand(CLI::App& app, int& exitCode);
void addBsdfCommand(CLI::App& app, int& exitCode);

// Every command of the lucent program, in the order its help lists them.
inline void addCommands(CLI::App& app, int& exitCode) {
  addRenderCommand(app, exitCode);
  addCompareCommand(app, exitCode);
  addMethodsCommand(app, exitCode);
  addMergeCommand(app, exitCode);
  addReportCommand(app, exitCode);
  addCheckDumpCommand(app, exitCode);
  addBsdfCommand(app, exitCode);
}
}  // namespace lucent::cli
