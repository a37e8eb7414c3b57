// `pdsm`: bake, query and inspect penumbra deep shadow maps, locally or on a coordinator.
#include <CLI/CLI.hpp>

#include "client/cli_common.h"
#include "client/commands.h"
#include "core/util/termination_cleanup.h"

int main(int argc, char** argv) {
  // Ctrl-C or a kill during a bake, fetch or sweep leaves no "OUT.tmp-XXXXXX" behind.
  pdsm::RemoveTempFilesOnTerminationSignals();
  CLI::App app{"pdsm: penumbra deep shadow maps (soft shadows from area lights)"};
  app.require_subcommand(1);
  int exit_code = pdsm::kExitOk;
  pdsm::RegisterBakeCommand(app, &exit_code);
  pdsm::RegisterQueryCommand(app, &exit_code);
  pdsm::RegisterInfoCommand(app, &exit_code);
  pdsm::RegisterReferenceCommand(app, &exit_code);
  pdsm::RegisterSweepCommand(app, &exit_code);
  pdsm::RegisterSubmitCommand(app, &exit_code);
  pdsm::RegisterJobCommands(app, &exit_code);
  pdsm::RegisterWatchCommand(app, &exit_code);
  pdsm::RegisterFetchCommand(app, &exit_code);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? pdsm::kExitOk : pdsm::kExitBadInput;
  }
  return exit_code;
}
