// The `samp` executable run as a child process by the tools tests: its exit
// status and standard error (SAMP_BINARY is the executable's path).
#pragma once

#include <sys/types.h>

#include <string>
#include <vector>

namespace samp::test {

// Starts `samp ARGS` with stdout and stderr into `log_prefix`.{out,err}; the
// child's pid (< 0 when fork failed).
pid_t StartSamp(const std::vector<std::string>& args, const std::string& log_prefix);

// Runs `samp ARGS`; returns the exit status (-1 when it did not exit) and
// its standard error.
int RunSamp(const std::vector<std::string>& args, const std::string& log_prefix, std::string* stderr_text);

// The last non-empty line of `text`.
std::string LastLine(const std::string& text);

}  // namespace samp::test
