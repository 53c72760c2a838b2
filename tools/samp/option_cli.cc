#include "tools/samp/option_cli.h"

#include <iostream>

#include "libsamp/core/log.h"

namespace samp::tools {

namespace {

const char* TypeName(OptionKind kind) {
  switch (kind) {
    case OptionKind::kInt:
    case OptionKind::kUnsigned:
      return "INT";
    case OptionKind::kNumber:
      return "FLOAT";
    case OptionKind::kChoice:
    case OptionKind::kText:
      return "TEXT";
    case OptionKind::kFlag:
      break;
  }
  return "";
}

CLI::Validator RuleValidator(const OptionInfo& info) {
  return CLI::Validator([info](std::string& text) { return info.Validate(text); }, info.rule_text);
}

void AddDeprecated(CLI::App* command, const OptionBinding& b, const std::string& prefix,
                   const std::string& old_flag, const std::string& value) {
  const std::string old_name = CommandLineName(old_flag, prefix);
  std::string now = CommandLineName(b.info.flag, prefix) + (value.empty() ? "" : " " + value);
  if (b.info.kind == OptionKind::kFlag && !value.empty()) {
    now = ParseOptionBool(value) ? CommandLineName(b.info.flag, prefix) : OffFlagName(b.info, prefix);
  }
  const std::string note = old_name + " is deprecated, use " + now;
  if (value.empty()) {
    command
        ->add_option_function<std::string>(
            old_name,
            [note, set = b.set](const std::string& text) {
              LogWarning() << note;
              set(text);
            },
            "Deprecated: use " + now)
        ->type_name(TypeName(b.info.kind))
        ->check(RuleValidator(b.info))
        ->group("Deprecated");
  } else {
    command
        ->add_flag_callback(
            old_name,
            [note, value, set = b.set] {
              LogWarning() << note;
              set(value);
            },
            "Deprecated: use " + now)
        ->group("Deprecated");
  }
}


CLI::Option* AddFlag(CLI::App* command, const OptionBinding& b, const std::string& name, const std::string& prefix) {
  const OptionInfo& info = b.info;
  switch (info.flag_names) {
    case FlagNames::kOnOnly:
      return command->add_flag(name, *b.flag, info.help);
    case FlagNames::kOffOnly:
      return command->add_flag_callback(OffFlagName(info, prefix), [flag = b.flag] { *flag = false; }, info.help);
    case FlagNames::kOnAndOff:
      break;
  }
  return command->add_flag(name + ",!" + OffFlagName(info, prefix), *b.flag, info.help)->default_str(info.default_text);
}

CLI::Option* AddValue(CLI::App* command, const OptionBinding& b, const std::string& name) {
  const OptionInfo& info = b.info;
  CLI::Option* option = nullptr;
  if (info.list) {
    // A list whose values do not make whole items (3 numbers each) is a usage error, as a bad value.
    option = command->add_option_function<std::vector<std::string>>(
        name,
        [set = b.set_list, name](const std::vector<std::string>& values) {
          try {
            set(values);
          } catch (const Error& e) {
            throw CLI::ValidationError(name, e.what());
          }
        },
        info.help);
    option->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
    if (info.arity > 1) option->expected(info.arity);
    if (info.separator != 0) option->delimiter(info.separator);
  } else {
    option = command->add_option_function<std::string>(
        name, [set = b.set](const std::string& text) { set(text); }, info.help);
  }
  option->type_name(TypeName(info.kind))->default_str(info.default_text)->check(RuleValidator(info));
  switch (info.path) {
    case OptionPath::kExistingFile:
      option->check(CLI::ExistingFile);
      break;
    case OptionPath::kExistingDirectory:
      option->check(CLI::ExistingDirectory);
      break;
    case OptionPath::kExistingPath:
      option->check(CLI::ExistingPath);
      break;
    case OptionPath::kAny:
      break;
  }
  if (info.required) option->required();
  return option;
}

}  // namespace

void AddTableOptions(CLI::App* command, const std::vector<OptionBinding>& bindings, const std::string& prefix,
                     const std::string& group) {
  for (const OptionBinding& b : bindings) {
    const OptionInfo& info = b.info;
    if (info.internal) continue;
    const std::string name = (info.short_flag != 0 ? "-" + std::string(1, info.short_flag) + "," : "") +
                             CommandLineName(info, prefix);
    CLI::Option* option =
        info.kind == OptionKind::kFlag ? AddFlag(command, b, name, prefix) : AddValue(command, b, name);
    option->group(group);
    for (const auto& [old_flag, value] : info.deprecated) AddDeprecated(command, b, prefix, old_flag, value);
  }
}

std::vector<OptionBinding> Only(const std::vector<OptionBinding>& bindings, const std::vector<std::string>& names) {
  std::vector<OptionBinding> picked;
  for (const std::string& name : names) {
    const size_t before = picked.size();
    for (const OptionBinding& b : bindings) {
      if (b.info.name == name) picked.push_back(b);
    }
    SAMP_CHECK(picked.size() == before + 1) << "no option " << name;
  }
  return picked;
}

void AddListOption(CLI::App* command, const std::vector<OptionBinding>& bindings, const std::string& name,
                   const std::vector<std::string>& fields, const std::string& help, const std::string& group) {
  std::vector<OptionBinding> parts;
  std::string defaults;
  for (const std::string& field : fields) {
    for (const OptionBinding& b : bindings) {
      if (b.info.name == field) parts.push_back(b);
    }
    SAMP_CHECK(!parts.empty() && parts.back().info.name == field) << name << ": no option " << field;
    defaults += (defaults.empty() ? "" : ",") + parts.back().info.default_text;
  }
  command
      ->add_option_function<std::vector<std::string>>(
          name,
          [parts, name](const std::vector<std::string>& values) {
            for (size_t i = 0; i < values.size(); ++i) {
              const std::string reason = parts[i].info.Validate(values[i]);
              if (!reason.empty()) throw CLI::ValidationError(name, parts[i].info.name + " " + reason);
              parts[i].set(values[i]);
            }
          },
          help)
      ->delimiter(',')
      ->expected(int(parts.size()))
      ->default_str(defaults)
      ->group(group);
}

void AddHelpOptions(CLI::App* command, const std::vector<OptionList>& lists) {
  std::vector<std::string> formats;
  for (const OptionList& list : lists) formats.push_back(list.format);
  command
      ->add_option_function<std::string>(
          "--help-options",
          [lists](const std::string& format) {
            for (const OptionList& list : lists) {
              if (list.format == format) std::cout << OptionsMarkdown(list.options, list.prefix);
            }
            throw CLI::Success();
          },
          "Print the option list of the docs (a Markdown table) and exit")
      ->check(CLI::IsMember(formats))
      ->trigger_on_parse();
}

}  // namespace samp::tools
