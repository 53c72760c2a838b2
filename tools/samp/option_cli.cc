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

}  // namespace

void AddTableOptions(CLI::App* command, const std::vector<OptionBinding>& bindings, const std::string& prefix,
                     const std::string& group) {
  for (const OptionBinding& b : bindings) {
    const OptionInfo& info = b.info;
    if (info.internal) continue;
    const std::string name =
        (info.short_flag != 0 ? "-" + std::string(1, info.short_flag) + "," : "") + CommandLineName(info.flag, prefix);
    if (info.kind == OptionKind::kFlag) {
      command->add_flag(name + ",!" + OffFlagName(info, prefix), *b.flag, info.help)
          ->default_str(info.default_text)
          ->group(group);
    } else {
      command
          ->add_option_function<std::string>(
              name, [set = b.set](const std::string& text) { set(text); }, info.help)
          ->type_name(TypeName(info.kind))
          ->default_str(info.default_text)
          ->check(RuleValidator(info))
          ->group(group);
    }
    for (const auto& [old_flag, value] : info.deprecated) AddDeprecated(command, b, prefix, old_flag, value);
  }
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
