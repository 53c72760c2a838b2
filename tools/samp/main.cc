// samp: shape and motion priors for 4D vehicle reconstruction.
// Dispatches to the subcommands declared in commands.h.
#include <exception>
#include <iostream>

#include "libsamp/core/atomic_file.h"
#include "libsamp/core/error.h"
#include "libsamp/core/log.h"
#include "tools/samp/commands.h"

namespace samp::tools {

void AddCommonOptions(CLI::App* command) {
  command->add_flag_callback("-v,--verbose", [] { SetLogLevel(LogLevel::kDebug); },
                             "Print debug messages");
  command->add_flag_callback("-q,--quiet", [] { SetLogLevel(LogLevel::kWarning); },
                             "Print only warnings and errors (no progress)");
}

}  // namespace samp::tools

int main(int argc, char** argv) {
  // SIGINT / SIGTERM remove the temporary files of outputs being written.
  samp::RemoveTemporariesOnSignal();
  CLI::App app{
      "samp: shape and motion priors for 4D vehicle reconstruction from stereo video\n"
      "(after Engelmann, Stueckler and Leibe, WACV 2017). Run `samp COMMAND --help`."};
  app.set_version_flag("--version", "samp 0.1.0");
  app.require_subcommand(1);
  // Subcommands (each in its own *_command.cc):
  samp::tools::RegisterTrainCommand(&app);
  samp::tools::RegisterInspectCommand(&app);
  samp::tools::RegisterFitCommand(&app);
  samp::tools::RegisterSynthCommand(&app);
  samp::tools::RegisterEvalCommand(&app);
  samp::tools::RegisterViewCommand(&app);
  samp::tools::RegisterCalibrateCommand(&app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const samp::Error& e) {
    std::cerr << "samp: error: " << e.what() << std::endl;
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "samp: unexpected error: " << e.what() << std::endl;
    return 2;
  }
  return 0;
}
