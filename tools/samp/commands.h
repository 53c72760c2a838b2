// Subcommands of the `samp` executable. Each Register* adds one subcommand to
// `app` with its options and a callback that calls into libsamp; errors
// propagate as samp::Error and are reported by main.
#pragma once

#include <CLI/CLI.hpp>

namespace samp::tools {

// Adds the options shared by every subcommand (--verbose, --quiet, --threads).
void AddCommonOptions(CLI::App* command);

void RegisterTrainCommand(CLI::App* app);
void RegisterInspectCommand(CLI::App* app);

void RegisterFitCommand(CLI::App* app);

void RegisterSynthCommand(CLI::App* app);
void RegisterEvalCommand(CLI::App* app);
void RegisterViewCommand(CLI::App* app);
void RegisterCalibrateCommand(CLI::App* app);

}  // namespace samp::tools
