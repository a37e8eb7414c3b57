// The `pdsm` subcommands. Each registers itself on the app; its callback stores the process
// exit code in *exit_code.
#ifndef PDSM_CLIENT_COMMANDS_H_
#define PDSM_CLIENT_COMMANDS_H_

#include <CLI/CLI.hpp>

namespace pdsm {

void RegisterBakeCommand(CLI::App& app, int* exit_code);
void RegisterQueryCommand(CLI::App& app, int* exit_code);
void RegisterInfoCommand(CLI::App& app, int* exit_code);
void RegisterExportImageCommand(CLI::App& app, int* exit_code);
void RegisterShadowmaskCommand(CLI::App& app, int* exit_code);
// Accuracy: the ground truth, the speed/accuracy sweep, where a bake's error lives.
void RegisterReferenceCommand(CLI::App& app, int* exit_code);
void RegisterSweepCommand(CLI::App& app, int* exit_code);
void RegisterCompareCommand(CLI::App& app, int* exit_code);
// The distributed service (a pdsm-coordinator at --server).
void RegisterSubmitCommand(CLI::App& app, int* exit_code);
void RegisterJobCommands(CLI::App& app, int* exit_code);  // status, list, cancel, stats
void RegisterWatchCommand(CLI::App& app, int* exit_code);
void RegisterFetchCommand(CLI::App& app, int* exit_code);

}  // namespace pdsm

#endif  // PDSM_CLIENT_COMMANDS_H_
