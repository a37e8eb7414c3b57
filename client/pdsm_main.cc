// `pdsm`: bake, query and inspect penumbra deep shadow maps, locally or on a coordinator.
#include <cstdio>

#include <CLI/CLI.hpp>

#include "client/cli_common.h"
#include "client/commands.h"
#include "core/util/termination_cleanup.h"
#include "core/util/version.h"

int main(int argc, char** argv) {
  // Ctrl-C or a kill during a bake, fetch or sweep leaves no "OUT.tmp-XXXXXX" behind.
  pdsm::RemoveTempFilesOnTerminationSignals();
  CLI::App app{"pdsm: penumbra deep shadow maps (soft shadows from area lights)"};
  app.set_version_flag("--version", pdsm::VersionLine("pdsm"));
  app.require_subcommand(1);
  int exit_code = pdsm::kExitOk;
  pdsm::RegisterBakeCommand(app, &exit_code);
  pdsm::RegisterQueryCommand(app, &exit_code);
  pdsm::RegisterInfoCommand(app, &exit_code);
  pdsm::RegisterExportImageCommand(app, &exit_code);
  pdsm::RegisterShadowmaskCommand(app, &exit_code);
  pdsm::RegisterReferenceCommand(app, &exit_code);
  pdsm::RegisterSweepCommand(app, &exit_code);
  pdsm::RegisterCompareCommand(app, &exit_code);
  pdsm::RegisterSubmitCommand(app, &exit_code);
  pdsm::RegisterJobCommands(app, &exit_code);
  pdsm::RegisterWatchCommand(app, &exit_code);
  pdsm::RegisterFetchCommand(app, &exit_code);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version are "errors" that succeed: CLI11 prints them.
    if (e.get_exit_code() == 0) return app.exit(e) == 0 ? pdsm::kExitOk : pdsm::kExitBadInput;
    // The flag parser's own messages ("--output is required", "Could not convert: ..."), in
    // the form of every other error, with where to look.
    std::fprintf(stderr, "pdsm: %s (see `pdsm --help` or `pdsm COMMAND --help`)\n", e.what());
    return pdsm::kExitBadInput;
  }
  return exit_code;
}
