// lucent check-dump REFERENCE_DIR CANDIDATE_DIR: another backend's stage dumps against Lucent's,
// array by array (lucent/render/dump_compare.h). Prints a line per differing array with its first
// differing records, then a JSON summary; exits 0 when every array compared agrees, 1 when one
// differs, 2 on an error (a directory that is not there, a file that is not a dump, nothing to
// compare).
#include <iostream>
#include <memory>
#include <sstream>

#include "cli/commands.h"
#include "lucent/core/text.h"
#include "lucent/render/dump_compare.h"

namespace lucent::cli {

void addCheckDumpCommand(CLI::App& app, int& exitCode) {
  auto reference = std::make_shared<std::string>(), candidate = std::make_shared<std::string>();
  auto options = std::make_shared<DumpCompareOptions>();
  CLI::App* cmd = app.add_subcommand("check-dump", "compare another backend's stage dumps with Lucent's, array by array "
                                                   "(docs/dump-format.md, Comparing dumps)");
  cmd->add_option("reference", *reference, "Lucent's dump directory")->required();
  cmd->add_option("candidate", *candidate, "the other backend's dump directory")->required();
  cmd->add_option("--relative", options->relative, "relative difference allowed between two floats")
      ->capture_default_str()->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--ulps", options->ulps, "or this many units in the last place")->capture_default_str();
  cmd->add_option("--report", options->reported, "differing records listed per array")->capture_default_str();
  cmd->callback([reference, candidate, options, &exitCode] {
    try {
      const DumpComparison c = compareDumpDirectories(*reference, *candidate, *options);
      if (c.arrays.empty())
        throw std::runtime_error("'" + *reference + "' and '" + *candidate + "' hold no dump of the same name");
      std::istringstream report(dumpComparisonReport(c));
      for (std::string line; std::getline(report, line);) std::cerr << "lucent check-dump: " << line << "\n";
      std::cout << dumpComparisonJson(c) << "\n";
      exitCode = c.passed() ? 0 : 1;
    } catch (const std::exception& e) {
      std::cerr << "lucent check-dump: error: " << printable(e.what()) << "\n";
      exitCode = 2;
    }
  });
}

}  // namespace lucent::cli
