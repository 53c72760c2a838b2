// samp: shape and motion priors for 4D vehicle reconstruction.
// Dispatches to the subcommands declared in commands.h.
#include <exception>
#include <new>
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

  // Exit status (docs/reliability.md, "Exit status"): 0 when everything asked
  // for was written; 1 when an input or a write failed (one line
  // `samp: error: ...`; nothing good was replaced); 2 for a usage error (an
  // unknown option, a missing or invalid argument), also with a
  // `samp: error: ...` line. --help and --version exit 0.
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::Success& e) {  // an option that prints and ends the run (--help-options)
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // CLI11's own codes (105, 106, 109, ...) and its message without a prefix.
    std::cerr << "samp: error: " << e.what() << "\nRun `samp --help` or `samp COMMAND --help` for the options."
              << std::endl;
    return 2;
  } catch (const samp::Error& e) {
    std::cerr << "samp: error: " << e.what() << std::endl;
    return 1;
  } catch (const std::bad_alloc&) {
    std::cerr << "samp: error: out of memory (an input larger than the memory budget?)" << std::endl;
    return 1;
  } catch (const std::exception& e) {
    // Not a samp::Error: a bug (tools/fuzz_cli.py reports these).
    std::cerr << "samp: error: internal error: " << e.what() << std::endl;
    return 1;
  }
  return 0;
}
