// One declaration per option (COLMAP's OptionManager is the model). An
// OptionTable<S> lists each field of an options struct once: its name, a
// pointer to the member, a one-line help and its rule (a range, positive, a
// list of choices, or a rule over several fields). The table drives
//  - Check(): throws "FitOptions.em_iterations must be >= 0, got -1";
//  - the JSON of a config file, through OptionsJson (core/json_fields.h):
//    Json(io, options) is the body of that struct's OptionFields();
//  - the command line: Bind(&options) gives one typed handle per field that a
//    parser registers (tools/samp/option_cli.h); the command-line name is the
//    field's name with '-' for '_' unless the table says otherwise, and a
//    renamed option keeps its old name as a deprecated alias;
//  - the option list of the docs: Markdown() (`samp fit --help-options markdown`).
// The default of a field is its value in a default-constructed S. A field
// marked Internal() is in the JSON and the docs but not on the command line.
// A table is built once and then only read (thread-safe for reading).
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <sstream>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "libsamp/core/error.h"
#include "libsamp/core/json_fields.h"

namespace samp {

// A numeric rule: an interval whose ends may be open, closed or absent; the
// value must also be finite.
struct NumberRule {
  bool has_min = false, min_open = false;
  double min = 0.0;
  bool has_max = false, max_open = false;
  double max = 0.0;
  bool Holds(double value) const;
  // ">= 0", "> 0", "<= 10", "in (0, 1.5708]"; "finite" without bounds.
  std::string Text() const;
};

enum class OptionKind { kFlag, kInt, kUnsigned, kNumber, kText, kChoice };

// A number as the docs and the messages show it (up to 6 significant digits).
std::string FormatOptionNumber(double value);

// What the command line and the docs know of one option.
struct OptionInfo {
  std::string name;      // JSON key path and the name in Check(): "motion_noise.sigma_yaw"
  std::string flag;      // command-line name without dashes: "em-iterations" (see CommandLineName)
  std::string off_flag;  // kFlag: the name that sets false ("huber-loss"; empty: see OffFlagName)
  char short_flag = 0;   // a one-letter name besides `flag` ('R' for -R), 0 = none
  // Old command-line names: (name, value). An empty value: the old option
  // takes a value; else it is a flag that sets this value.
  std::vector<std::pair<std::string, std::string>> deprecated;
  std::string help;
  OptionKind kind = OptionKind::kNumber;
  std::string default_text;
  std::string rule_text;  // every rule of the field, "; "-joined (empty: none)
  NumberRule number_rule;
  std::vector<std::string> choices;  // kText / kChoice; empty = free text
  bool internal = false;
  // "" when `text` is a valid command-line value of this option, else the reason.
  std::string Validate(const std::string& text) const;
};

// One field of one options object, for a command-line parser.
struct OptionBinding {
  OptionInfo info;
  bool* flag = nullptr;  // kFlag: the field
  // Parses `text` (already validated) into the field.
  std::function<void(const std::string& text)> set;
};

// The command-line name of `flag` ("--" + prefix + flag); a flag that starts
// with "--" already is taken as it is (a name kept from before the table).
std::string CommandLineName(const std::string& flag, const std::string& prefix);
// kFlag: the name that sets false: CommandLineName(off_flag, prefix), or
// "--no-" + prefix + flag without an off_flag.
std::string OffFlagName(const OptionInfo& info, const std::string& prefix);

// Markdown table of options: option, command line (names with `prefix`),
// default, rule, meaning.
std::string OptionsMarkdown(const std::vector<OptionInfo>& options, const std::string& prefix = "");

template <typename S>
class OptionTable {
 public:
  explicit OptionTable(std::string struct_name) : struct_name_(std::move(struct_name)) {}

  // Completes the field just added (returned by Add*); valid while the table lives.
  class Entry {
   public:
    Entry(OptionTable* table, size_t index) : table_(table), index_(index) {}
    // The command-line name instead of the field's ("--name": not prefixed).
    Entry& Flag(std::string flag) { return Info([&](OptionInfo& i) { i.flag = std::move(flag); }); }
    Entry& OffFlag(std::string flag) { return Info([&](OptionInfo& i) { i.off_flag = std::move(flag); }); }
    // A one-letter command-line name besides the long one (-R).
    Entry& Short(char letter) { return Info([&](OptionInfo& i) { i.short_flag = letter; }); }
    // An old command-line name that still works and prints a note; `value`: see OptionInfo.
    Entry& Deprecated(std::string old_flag, std::string value = "") {
      return Info([&](OptionInfo& i) { i.deprecated.emplace_back(std::move(old_flag), std::move(value)); });
    }
    Entry& Internal() { return Info([](OptionInfo& i) { i.internal = true; }); }
    Entry& AtLeast(double min) { return Bound(true, min, false); }
    Entry& Above(double min) { return Bound(true, min, true); }
    Entry& AtMost(double max) { return Bound(false, max, false); }
    Entry& Below(double max) { return Bound(false, max, true); }
    Entry& Positive() { return Above(0.0); }
    Entry& NonNegative() { return AtLeast(0.0); }
    Entry& Choices(std::vector<std::string> choices) {
      return Info([&](OptionInfo& i) { i.choices = std::move(choices); });
    }
    // A rule over the whole struct (e.g. against another field), checked by Check() only.
    Entry& Rule(std::string text, std::function<bool(const S&)> holds) {
      table_->fields_[index_].rules.emplace_back(std::move(text), std::move(holds));
      return *this;
    }

   private:
    template <typename F>
    Entry& Info(F edit) {
      edit(table_->fields_[index_].info);
      return *this;
    }
    Entry& Bound(bool lower, double value, bool open) {
      NumberRule& r = table_->fields_[index_].info.number_rule;
      (lower ? r.has_min : r.has_max) = true;
      (lower ? r.min : r.max) = value;
      (lower ? r.min_open : r.max_open) = open;
      return *this;
    }
    OptionTable* table_;
    size_t index_;
  };

  // bool, int, uint64_t (seeds), double or std::string members.
  template <typename T>
  Entry Add(const std::string& name, T S::*member, std::string help) {
    static_assert(std::is_same_v<T, bool> || std::is_same_v<T, int> || std::is_same_v<T, std::uint64_t> ||
                      std::is_same_v<T, double> || std::is_same_v<T, std::string>,
                  "OptionTable::Add: bool, int, uint64_t, double or std::string");
    Field f = NewField(name, std::move(help));
    f.info.kind = std::is_same_v<T, bool>             ? OptionKind::kFlag
                  : std::is_same_v<T, int>            ? OptionKind::kInt
                  : std::is_same_v<T, std::uint64_t>  ? OptionKind::kUnsigned
                  : std::is_same_v<T, double>         ? OptionKind::kNumber
                                                      : OptionKind::kText;
    if constexpr (std::is_same_v<T, bool>) {
      f.flag = [member](S* s) { return &(s->*member); };
    }
    if constexpr (std::is_same_v<T, int> || std::is_same_v<T, std::uint64_t> || std::is_same_v<T, double>) {
      f.number = [member](const S& s) { return double(s.*member); };
    }
    f.text = [member](const S& s) { return ValueText(s.*member); };
    f.set = [member](S* s, const std::string& text) { s->*member = ParseValue<T>(text); };
    f.copy = [member](const S& from, S* to) { to->*member = from.*member; };
    json_.push_back([member, name](OptionsJson& io, S& s) { io(name, s.*member); });
    fields_.push_back(std::move(f));
    return Entry(this, fields_.size() - 1);
  }

  // As Add, but the JSON holds the field only when it differs from its default,
  // so that files written before the field existed keep their bytes.
  template <typename T>
  Entry AddOptional(const std::string& name, T S::*member, std::string help) {
    return AddOptional(name, member, std::move(help), S{}.*member);
  }
  // The same with the default given (a struct whose S{} GCC 12 wrongly takes
  // for uninitialised in this template: -Wmaybe-uninitialized).
  template <typename T>
  Entry AddOptional(const std::string& name, T S::*member, std::string help, const T& default_value) {
    Entry entry = Add(name, member, std::move(help));
    json_.back() = [member, name, default_value](OptionsJson& io, S& s) {
      io.Optional(name, s.*member, default_value);
    };
    return entry;
  }

  // An enum written by its name (to_name(E) -> const char*, from_name(std::string) -> E).
  template <typename E>
  Entry AddChoice(const std::string& name, E S::*member, const char* (*to_name)(E),
                  E (*from_name)(const std::string&), std::vector<std::string> choices, std::string help) {
    Field f = NewField(name, std::move(help));
    f.info.kind = OptionKind::kChoice;
    f.info.choices = std::move(choices);
    f.text = [member, to_name](const S& s) { return std::string(to_name(s.*member)); };
    f.set = [member, from_name](S* s, const std::string& text) { s->*member = from_name(text); };
    f.copy = [member](const S& from, S* to) { to->*member = from.*member; };
    json_.push_back([member, name, to_name, from_name](OptionsJson& io, S& s) {
      io.Named(name, s.*member, to_name, from_name);
    });
    fields_.push_back(std::move(f));
    return Entry(this, fields_.size() - 1);
  }

  // As AddChoice, but the JSON holds the field only when it differs from its
  // default (as AddOptional).
  template <typename E>
  Entry AddOptionalChoice(const std::string& name, E S::*member, const char* (*to_name)(E),
                          E (*from_name)(const std::string&), std::vector<std::string> choices, std::string help) {
    Entry entry = AddChoice(name, member, to_name, from_name, std::move(choices), std::move(help));
    const E default_value = S{}.*member;
    json_.back() = [member, name, to_name, from_name, default_value](OptionsJson& io, S& s) {
      io.OptionalNamed(name, s.*member, default_value, to_name, from_name);
    };
    return entry;
  }

  // The fields of a nested struct, as an object `name` in the JSON, with the
  // names "name.field" and the command-line names flag_prefix + the child's.
  template <typename N>
  void AddNested(const std::string& name, N S::*member, const OptionTable<N>& child,
                 const std::string& flag_prefix) {
    auto shared = std::make_shared<OptionTable<N>>(child);
    AddNestedJson(name, member, [shared](OptionsJson& io, N& n) { shared->Json(io, n); });
    AddNestedFields(name, member, child, flag_prefix);
  }

  // As AddNested, but the JSON of the nested struct is its OptionFields(io, N&),
  // for a struct with fields besides its table's (a list).
  template <typename N>
  void AddNestedWithOptionFields(const std::string& name, N S::*member, const OptionTable<N>& child,
                                 const std::string& flag_prefix) {
    AddNestedJson(name, member, [](OptionsJson& io, N& n) { OptionFields(io, n); });
    AddNestedFields(name, member, child, flag_prefix);
  }

  const std::string& struct_name() const { return struct_name_; }

  // Throws samp::Error "StructName.field must be <rule>, got <value>" for the
  // first field that breaks its rule.
  void Check(const S& options) const {
    for (const Field& f : fields_) {
      const OptionInfo& i = f.info;
      if (f.number && !i.number_rule.Holds(f.number(options))) Fail(f, options, i.number_rule.Text());
      if (!i.choices.empty() && !Contains(i.choices, f.text(options))) Fail(f, options, ChoicesText(i.choices));
      for (const auto& [text, holds] : f.rules) {
        if (!holds(options)) Fail(f, options, text);
      }
    }
  }

  // Copies the field `name` (OptionInfo::name) from `from` to `to`; throws
  // for a name the table does not have. (Options given on a command line
  // laid over a preset: `samp synth --preset`.)
  void Copy(const std::string& name, const S& from, S* to) const {
    for (const Field& f : fields_) {
      if (f.info.name == name) return f.copy(from, to);
    }
    SAMP_THROW() << struct_name_ << " has no option " << name;
  }

  // Every field for config.json's writer or reader (OptionsJson).
  void Json(OptionsJson& io, S& options) const {
    for (const auto& visit : json_) visit(io, options);
  }

  // Every field with its default (that of a default-constructed S).
  std::vector<OptionInfo> Describe() const {
    // On the heap: GCC 12 takes a large S on the stack here for uninitialised
    // (a false -Wmaybe-uninitialized).
    const auto defaults = std::make_unique<const S>();
    std::vector<OptionInfo> infos;
    for (const Field& f : fields_) infos.push_back(Described(f, *defaults));
    return infos;
  }

  // Handles on the fields of `options` (which must outlive them); defaults:
  // the values in `options`.
  std::vector<OptionBinding> Bind(S* options) const {
    std::vector<OptionBinding> bindings;
    for (const Field& f : fields_) {
      OptionBinding b;
      b.info = Described(f, *options);
      if (f.flag) b.flag = f.flag(options);
      b.set = [options, set = f.set](const std::string& text) { set(options, text); };
      bindings.push_back(std::move(b));
    }
    return bindings;
  }

 private:
  template <typename>
  friend class OptionTable;

  struct Field {
    OptionInfo info;
    std::function<bool*(S*)> flag;                  // kFlag
    std::function<double(const S&)> number;         // kInt, kNumber
    std::function<std::string(const S&)> text;      // the value as text
    std::function<void(S*, const std::string&)> set;  // parses text
    std::function<void(const S&, S*)> copy;            // the field from one object to another
    std::vector<std::pair<std::string, std::function<bool(const S&)>>> rules;
  };

  template <typename N, typename Visit>
  void AddNestedJson(const std::string& name, N S::*member, Visit visit) {
    json_.push_back([member, name, visit](OptionsJson& io, S& s) {
      io.NestedWith(name, [&](OptionsJson& child_io) { visit(child_io, s.*member); });
    });
  }

  // The child's fields as this table's, named "name.field", flags prefixed.
  template <typename N>
  void AddNestedFields(const std::string& name, N S::*member, const OptionTable<N>& child,
                       const std::string& flag_prefix) {
    for (const typename OptionTable<N>::Field& c : child.fields_) {
      Field f;
      f.info = c.info;
      f.info.name = name + "." + c.info.name;
      auto prefixed = [&flag_prefix](const std::string& flag) {
        return flag.rfind("--", 0) == 0 ? flag : flag_prefix + flag;
      };
      f.info.flag = prefixed(c.info.flag);
      if (!c.info.off_flag.empty()) f.info.off_flag = prefixed(c.info.off_flag);
      for (auto& d : f.info.deprecated) d.first = prefixed(d.first);
      if (c.flag) f.flag = [member, g = c.flag](S* s) { return g(&(s->*member)); };
      if (c.number) f.number = [member, g = c.number](const S& s) { return g(s.*member); };
      f.text = [member, g = c.text](const S& s) { return g(s.*member); };
      f.set = [member, g = c.set](S* s, const std::string& text) { g(&(s->*member), text); };
      f.copy = [member, g = c.copy](const S& from, S* to) { g(from.*member, &(to->*member)); };
      for (const auto& [text, holds] : c.rules) {
        f.rules.emplace_back(text, [member, h = holds](const S& s) { return h(s.*member); });
      }
      fields_.push_back(std::move(f));
    }
  }

  Field NewField(const std::string& name, std::string help) const {
    Field f;
    f.info.name = name;
    f.info.flag = name;
    for (char& c : f.info.flag) c = c == '_' ? '-' : c;
    f.info.help = std::move(help);
    return f;
  }

  static OptionInfo Described(const Field& f, const S& values) {
    OptionInfo i = f.info;
    i.default_text = f.text(values);
    std::string rule;
    if (f.number && (i.number_rule.has_min || i.number_rule.has_max)) rule = i.number_rule.Text();
    if (!i.choices.empty()) rule = ChoicesText(i.choices);
    for (const auto& r : f.rules) rule += (rule.empty() ? "" : "; ") + r.first;
    i.rule_text = rule;
    return i;
  }

  [[noreturn]] void Fail(const Field& f, const S& options, const std::string& rule) const {
    SAMP_THROW() << struct_name_ << "." << f.info.name << " must be " << rule << ", got "
                 << f.text(options);
  }

  static bool Contains(const std::vector<std::string>& list, const std::string& value) {
    for (const std::string& s : list) {
      if (s == value) return true;
    }
    return false;
  }
  static std::string ChoicesText(const std::vector<std::string>& choices) {
    std::string text = "one of ";
    for (size_t k = 0; k < choices.size(); ++k) text += (k ? ", " : "") + choices[k];
    return text;
  }

  static std::string ValueText(bool v) { return v ? "true" : "false"; }
  static std::string ValueText(int v) { return std::to_string(v); }
  static std::string ValueText(std::uint64_t v) { return std::to_string(v); }
  static std::string ValueText(double v) { return FormatOptionNumber(v); }
  static std::string ValueText(const std::string& v) { return v; }

  template <typename T>
  static T ParseValue(const std::string& text);

  std::string struct_name_;
  std::vector<Field> fields_;
  std::vector<std::function<void(OptionsJson&, S&)>> json_;
};

// Parsing of command-line text (throws samp::Error for malformed text).
bool ParseOptionBool(const std::string& text);
int ParseOptionInt(const std::string& text);
std::uint64_t ParseOptionUnsigned(const std::string& text);
double ParseOptionDouble(const std::string& text);

template <typename S>
template <typename T>
T OptionTable<S>::ParseValue(const std::string& text) {
  if constexpr (std::is_same_v<T, bool>) return ParseOptionBool(text);
  if constexpr (std::is_same_v<T, int>) return ParseOptionInt(text);
  if constexpr (std::is_same_v<T, std::uint64_t>) return ParseOptionUnsigned(text);
  if constexpr (std::is_same_v<T, double>) return ParseOptionDouble(text);
  if constexpr (std::is_same_v<T, std::string>) return text;
}

}  // namespace samp
