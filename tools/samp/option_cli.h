// Command-line options from an option table (libsamp/core/option_table.h):
// every field not marked internal becomes one CLI11 option named as the table
// says (or a positional argument), with its help, its default and its rule
// checked at parse time (a path: that it exists, as the table says; a list:
// each value); a field's deprecated names still work and print a note naming
// the new one.
#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "libsamp/core/option_table.h"

namespace samp::tools {

// `bindings` point into an options struct that must outlive `command`. The
// command-line names are CommandLineName(flag, prefix); `group` titles the
// options in --help.
void AddTableOptions(CLI::App* command, const std::vector<OptionBinding>& bindings, const std::string& prefix,
                     const std::string& group);

// The bindings named `names` (OptionInfo::name), in that order: a part of a
// table registered at its place among other options or in its own group.
std::vector<OptionBinding> Only(const std::vector<OptionBinding>& bindings, const std::vector<std::string>& names);

// `name` A,B,...: sets the fields `fields` (names in `bindings`) at once, each checked by its rule.
void AddListOption(CLI::App* command, const std::vector<OptionBinding>& bindings, const std::string& name,
                   const std::vector<std::string>& fields, const std::string& help, const std::string& group);

// One table's option list for the docs.
struct OptionList {
  std::string format;  // the value of --help-options that prints it
  std::vector<OptionInfo> options;
  std::string prefix;  // of the command-line names
};
// --help-options FORMAT: prints that list as Markdown (OptionsMarkdown) and exits.
void AddHelpOptions(CLI::App* command, const std::vector<OptionList>& lists);

}  // namespace samp::tools
