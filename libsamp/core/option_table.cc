#include "libsamp/core/option_table.h"

#include <cerrno>
#include <cstdlib>
#include <limits>

namespace samp {

bool NumberRule::Holds(double value) const {
  if (!std::isfinite(value)) return false;
  if (has_min && (min_open ? !(value > min) : !(value >= min))) return false;
  if (has_max && (max_open ? !(value < max) : !(value <= max))) return false;
  return true;
}

std::string NumberRule::Text() const {
  if (has_min && has_max) {
    return std::string("in ") + (min_open ? "(" : "[") + FormatOptionNumber(min) + ", " + FormatOptionNumber(max) +
           (max_open ? ")" : "]");
  }
  if (has_min) return std::string(min_open ? "> " : ">= ") + FormatOptionNumber(min);
  if (has_max) return std::string(max_open ? "< " : "<= ") + FormatOptionNumber(max);
  return "finite";
}

std::string FormatOptionNumber(double value) {
  std::ostringstream s;
  s << value;
  return s.str();
}

bool ParseOptionBool(const std::string& text) {
  if (text == "true" || text == "1" || text == "on" || text == "yes") return true;
  if (text == "false" || text == "0" || text == "off" || text == "no") return false;
  SAMP_THROW() << "'" << text << "' is not true or false";
}

int ParseOptionInt(const std::string& text) {
  char* end = nullptr;
  errno = 0;
  const long value = std::strtol(text.c_str(), &end, 10);
  SAMP_CHECK(!text.empty() && *end == '\0' && errno == 0 && value >= std::numeric_limits<int>::min() &&
             value <= std::numeric_limits<int>::max())
      << "'" << text << "' is not an integer";
  return int(value);
}

std::uint64_t ParseOptionUnsigned(const std::string& text) {
  char* end = nullptr;
  errno = 0;
  const unsigned long long value = std::strtoull(text.c_str(), &end, 10);
  SAMP_CHECK(!text.empty() && text[0] >= '0' && text[0] <= '9' && *end == '\0' && errno == 0)
      << "'" << text << "' is not a whole number >= 0";
  return std::uint64_t(value);
}

double ParseOptionDouble(const std::string& text) {
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  SAMP_CHECK(!text.empty() && *end == '\0') << "'" << text << "' is not a number";
  return value;
}

std::string JoinOptionList(const std::vector<std::string>& values) {
  std::string text;
  for (size_t k = 0; k < values.size(); ++k) text += (k ? "," : "") + values[k];
  return text;
}

std::vector<std::string> SplitOptionList(const std::string& text) {
  std::vector<std::string> values;
  if (text.empty()) return values;
  size_t start = 0;
  for (size_t comma = text.find(','); comma != std::string::npos; comma = text.find(',', start)) {
    values.push_back(text.substr(start, comma - start));
    start = comma + 1;
  }
  values.push_back(text.substr(start));
  return values;
}

std::string OptionInfo::Validate(const std::string& text) const {
  try {
    double number = 0.0;
    switch (kind) {
      case OptionKind::kFlag:
        ParseOptionBool(text);
        return "";
      case OptionKind::kInt:
        number = ParseOptionInt(text);
        break;
      case OptionKind::kUnsigned:
        number = double(ParseOptionUnsigned(text));
        break;
      case OptionKind::kNumber:
        number = ParseOptionDouble(text);
        break;
      case OptionKind::kText:
      case OptionKind::kChoice:
        if (choices.empty() || (empty_choice && text.empty())) return "";
        for (const std::string& c : choices) {
          if (c == text) return "";
        }
        return "must be " + rule_text + ", got '" + text + "'";
    }
    if (!number_rule.Holds(number)) return "must be " + number_rule.Text() + ", got " + text;
    return "";
  } catch (const Error& e) {
    return e.what();
  }
}

namespace {

std::string CommandLine(const OptionInfo& o, const std::string& prefix) {
  if (o.internal) return "internal";
  std::string text = "`" + CommandLineName(o, prefix) + "`";
  if (o.kind == OptionKind::kFlag && o.flag_names == FlagNames::kOffOnly) text = "`" + OffFlagName(o, prefix) + "`";
  if (o.short_flag != 0) text = "`-" + std::string(1, o.short_flag) + "`, " + text;
  if (o.kind == OptionKind::kFlag && o.flag_names == FlagNames::kOnAndOff) text += ", `" + OffFlagName(o, prefix) + "`";
  if (o.positional) text += " (positional)";
  if (o.list) {
    text += o.arity > 1 ? " " + std::to_string(o.arity) + " values" : "";
    text += o.separator == ',' ? " (comma-separated)"
            : o.separator != 0 ? std::string(" (") + o.separator + "-separated)"
                               : " (repeatable)";
  }
  if (o.required) text += ", required";
  std::string old;
  for (const auto& [flag, value] : o.deprecated) {
    old += (old.empty() ? "" : ", ") + ("`" + CommandLineName(flag, prefix) + "`") + (value.empty() ? "" : " = " + value);
  }
  if (!old.empty()) text += " (deprecated: " + old + ")";
  return text;
}

// The rules of the docs: the table's and that of a path.
std::string RuleColumn(const OptionInfo& o) {
  const char* path = o.path == OptionPath::kExistingFile        ? "an existing file"
                     : o.path == OptionPath::kExistingDirectory ? "an existing folder"
                     : o.path == OptionPath::kExistingPath      ? "an existing file or folder"
                                                                : "";
  if (*path == '\0') return o.rule_text;
  return o.rule_text.empty() ? path : o.rule_text + "; " + path;
}

std::string Escaped(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '|') out += '\\';
    out += c;
  }
  return out;
}

}  // namespace

std::string CommandLineName(const std::string& flag, const std::string& prefix) {
  return flag.rfind("--", 0) == 0 ? flag : "--" + prefix + flag;
}

std::string CommandLineName(const OptionInfo& info, const std::string& prefix) {
  return info.positional ? info.flag : CommandLineName(info.flag, prefix);
}

std::string OffFlagName(const OptionInfo& info, const std::string& prefix) {
  if (!info.off_flag.empty()) return CommandLineName(info.off_flag, prefix);
  return "--no-" + CommandLineName(info.flag, prefix).substr(2);
}

std::string OptionsMarkdown(const std::vector<OptionInfo>& options, const std::string& prefix) {
  std::ostringstream s;
  s << "| option | command line | default | rule | meaning |\n";
  s << "|---|---|---|---|---|\n";
  for (const OptionInfo& o : options) {
    s << "| " << o.name << " | " << CommandLine(o, prefix) << " | " << Escaped(o.default_text) << " | "
      << Escaped(RuleColumn(o)) << " | " << Escaped(o.help) << " |\n";
  }
  return s.str();
}

}  // namespace samp
