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
// marked Internal() is in the JSON and the docs but not on the command line;
// one marked NotInJson() (a run's plumbing: output paths, threads) is on the
// command line and in the docs but not in the JSON. Besides scalars a table
// holds lists (AddList: repeated or separated on the command line) and
// computed fields (AddComputed: a value the command line sets through a
// function of the struct, e.g. a grid from its voxel size). A command-line
// option may be positional, required, and for a path, one that must exist
// (checked on the command line only: the library reports a missing input
// when it reads it).
// A table is built once and then only read (thread-safe for reading).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <sstream>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <Eigen/Core>

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

// A path the command line requires to exist.
enum class OptionPath { kAny, kExistingFile, kExistingDirectory, kExistingPath };

// The command-line names of a kFlag: both (--x and --no-x), or one of them.
enum class FlagNames { kOnAndOff, kOnOnly, kOffOnly };

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
  OptionKind kind = OptionKind::kNumber;  // of a list: of its values
  std::string default_text;  // a list: its values ","-joined
  std::string rule_text;  // every rule of the field, "; "-joined (empty: none)
  NumberRule number_rule;  // of a list: of each of its numbers
  std::vector<std::string> choices;  // kText / kChoice; empty = free text
  bool empty_choice = false;          // "" is valid besides the choices (ChoicesOrEmpty)
  bool internal = false;
  bool in_json = true;      // false: NotInJson()
  bool positional = false;  // `flag` is the positional argument's name ("CAD_FOLDER")
  bool required = false;    // required on the command line
  OptionPath path = OptionPath::kAny;
  FlagNames flag_names = FlagNames::kOnAndOff;
  // A list: each command-line occurrence gives `arity` values; with a
  // separator, one value may hold several ("0,10,20").
  bool list = false;
  int arity = 1;
  char separator = 0;
  // "" when `text` is a valid command-line value of this option (of a list:
  // one of its values), else the reason.
  std::string Validate(const std::string& text) const;
};

// One field of one options object, for a command-line parser.
struct OptionBinding {
  OptionInfo info;
  bool* flag = nullptr;  // kFlag: the field
  // Parses `text` (already validated) into the field; a list: its values
  // ","-separated.
  std::function<void(const std::string& text)> set;
  // A list: sets the field to these values (each already validated).
  std::function<void(const std::vector<std::string>& values)> set_list;
};

// The command-line name of `flag` ("--" + prefix + flag); a flag that starts
// with "--" already is taken as it is (a name kept from before the table).
std::string CommandLineName(const std::string& flag, const std::string& prefix);
// The command-line name of an option: CommandLineName, or a positional's name.
std::string CommandLineName(const OptionInfo& info, const std::string& prefix);
// kFlag: the name that sets false: CommandLineName(off_flag, prefix), or
// "--no-" + prefix + flag without an off_flag.
std::string OffFlagName(const OptionInfo& info, const std::string& prefix);

// Markdown table of options: option, command line (names with `prefix`),
// default, rule, meaning.
std::string OptionsMarkdown(const std::vector<OptionInfo>& options, const std::string& prefix = "");

// The values of a list as text: ","-joined; and back (SplitOptionList("") is empty).
std::string JoinOptionList(const std::vector<std::string>& values);
std::vector<std::string> SplitOptionList(const std::string& text);

// Parsing of command-line text (throws samp::Error for malformed text).
bool ParseOptionBool(const std::string& text);
int ParseOptionInt(const std::string& text);
std::uint64_t ParseOptionUnsigned(const std::string& text);
double ParseOptionDouble(const std::string& text);

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
    // On the command line and in the docs, not in the JSON (a run's plumbing).
    Entry& NotInJson() {
      table_->RemoveJson(index_);
      return Info([](OptionInfo& i) { i.in_json = false; });
    }
    // The JSON is always written; a JSON without the key (a file written
    // before the field existed) reads the default.
    Entry& DefaultWhenAbsent() {
      table_->DefaultWhenAbsent(index_);
      return *this;
    }
    // A positional argument named `name` on the command line.
    Entry& Positional(std::string name) {
      return Info([&](OptionInfo& i) {
        i.flag = std::move(name);
        i.positional = true;
      });
    }
    // Required on the command line; Check(): "must be given" when empty.
    Entry& Required() { return Info([](OptionInfo& i) { i.required = true; }); }
    Entry& ExistingFile() { return Info([](OptionInfo& i) { i.path = OptionPath::kExistingFile; }); }
    Entry& ExistingDirectory() { return Info([](OptionInfo& i) { i.path = OptionPath::kExistingDirectory; }); }
    Entry& ExistingPath() { return Info([](OptionInfo& i) { i.path = OptionPath::kExistingPath; }); }
    // A kFlag with only its name that sets true (--link-only), or only the one that sets false.
    Entry& OnOnly() { return Info([](OptionInfo& i) { i.flag_names = FlagNames::kOnOnly; }); }
    Entry& OffOnly() { return Info([](OptionInfo& i) { i.flag_names = FlagNames::kOffOnly; }); }
    // A list: one command-line value may hold several, separated by `separator`.
    Entry& Separator(char separator) { return Info([&](OptionInfo& i) { i.separator = separator; }); }
    Entry& AtLeast(double min) { return Bound(true, min, false); }
    Entry& Above(double min) { return Bound(true, min, true); }
    Entry& AtMost(double max) { return Bound(false, max, false); }
    Entry& Below(double max) { return Bound(false, max, true); }
    Entry& Positive() { return Above(0.0); }
    Entry& NonNegative() { return AtLeast(0.0); }
    Entry& Choices(std::vector<std::string> choices) {
      return Info([&](OptionInfo& i) { i.choices = std::move(choices); });
    }
    // One of `choices` or empty (none).
    Entry& ChoicesOrEmpty(std::vector<std::string> choices) {
      return Info([&](OptionInfo& i) {
        i.choices = std::move(choices);
        i.empty_choice = true;
      });
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
    json_.push_back({fields_.size(), [member, name](OptionsJson& io, S& s) { io(name, s.*member); }});
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
    json_.back().visit = [member, name, default_value](OptionsJson& io, S& s) {
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
    json_.push_back({fields_.size(), [member, name, to_name, from_name](OptionsJson& io, S& s) {
                       io.Named(name, s.*member, to_name, from_name);
                     }});
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
    json_.back().visit = [member, name, to_name, from_name, default_value](OptionsJson& io, S& s) {
      io.OptionalNamed(name, s.*member, default_value, to_name, from_name);
    };
    return entry;
  }

  // A list of std::string, double or Eigen::Vector3d (3 numbers a value on the
  // command line: --size-variant 1.1 1 1); the JSON holds an array (of
  // 3-arrays). On the command line each occurrence adds values (see Separator).
  template <typename E>
  Entry AddList(const std::string& name, std::vector<E> S::*member, std::string help) {
    static_assert(std::is_same_v<E, std::string> || std::is_same_v<E, double> || std::is_same_v<E, Eigen::Vector3d>,
                  "OptionTable::AddList: std::string, double or Eigen::Vector3d");
    Field f = NewField(name, std::move(help));
    f.info.kind = std::is_same_v<E, std::string> ? OptionKind::kText : OptionKind::kNumber;
    f.info.list = true;
    f.info.arity = std::is_same_v<E, Eigen::Vector3d> ? 3 : 1;
    if constexpr (!std::is_same_v<E, std::string>) {
      f.numbers = [member](const S& s) { return ListNumbers(s.*member); };
    }
    f.text = [member](const S& s) { return ListText(s.*member); };
    f.set_list = [member, name](S* s, const std::vector<std::string>& values) {
      s->*member = ParseList<E>(name, values);
    };
    f.set = [set_list = f.set_list](S* s, const std::string& text) { set_list(s, SplitOptionList(text)); };
    f.copy = [member](const S& from, S* to) { to->*member = from.*member; };
    json_.push_back({fields_.size(), [member, name](OptionsJson& io, S& s) { ListJson(io, name, s.*member); }});
    fields_.push_back(std::move(f));
    return Entry(this, fields_.size() - 1);
  }

  // A value that is no member but a function of the struct (int or double):
  // `get` reads it, `set` sets the members it stands for. Not in the JSON
  // (which holds those members).
  template <typename T>
  Entry AddComputed(const std::string& name, std::function<T(const S&)> get, std::function<void(S*, T)> set,
                    std::string help) {
    static_assert(std::is_same_v<T, int> || std::is_same_v<T, double>, "OptionTable::AddComputed: int or double");
    Field f = NewField(name, std::move(help));
    f.info.kind = std::is_same_v<T, int> ? OptionKind::kInt : OptionKind::kNumber;
    f.info.in_json = false;
    f.number = [get](const S& s) { return double(get(s)); };
    f.text = [get](const S& s) { return ValueText(get(s)); };
    f.set = [set](S* s, const std::string& text) { set(s, ParseValue<T>(text)); };
    f.copy = [get, set](const S& from, S* to) { set(to, get(from)); };
    fields_.push_back(std::move(f));
    return Entry(this, fields_.size() - 1);
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
      if (i.required && f.text(options).empty()) Fail(f, options, "given");
      if (f.number && !i.number_rule.Holds(f.number(options))) Fail(f, options, i.number_rule.Text());
      if (f.numbers) {
        for (double x : f.numbers(options)) {
          if (!i.number_rule.Holds(x)) Fail(f, options, i.number_rule.Text());
        }
      }
      if (!i.choices.empty() && !IsChoice(i, f.text(options))) Fail(f, options, ChoicesText(i));
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
    for (const JsonVisit& j : json_) j.visit(io, options);
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
      if (f.set_list) {
        b.set_list = [options, set = f.set_list](const std::vector<std::string>& values) { set(options, values); };
      }
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
    std::function<std::vector<double>(const S&)> numbers;  // a list of numbers
    std::function<std::string(const S&)> text;      // the value as text
    std::function<void(S*, const std::string&)> set;  // parses text
    std::function<void(S*, const std::vector<std::string>&)> set_list;  // a list: parses its values
    std::function<void(const S&, S*)> copy;            // the field from one object to another
    std::vector<std::pair<std::string, std::function<bool(const S&)>>> rules;
  };

  template <typename N, typename Visit>
  void AddNestedJson(const std::string& name, N S::*member, Visit visit) {
    json_.push_back({kNoField, [member, name, visit](OptionsJson& io, S& s) {
                       io.NestedWith(name, [&](OptionsJson& child_io) { visit(child_io, s.*member); });
                     }});
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
      if (c.numbers) f.numbers = [member, g = c.numbers](const S& s) { return g(s.*member); };
      if (c.set_list) {
        f.set_list = [member, g = c.set_list](S* s, const std::vector<std::string>& v) { g(&(s->*member), v); };
      }
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
    if ((f.number || f.numbers) && (i.number_rule.has_min || i.number_rule.has_max)) rule = i.number_rule.Text();
    if (!i.choices.empty()) rule = ChoicesText(i);
    for (const auto& r : f.rules) rule += (rule.empty() ? "" : "; ") + r.first;
    i.rule_text = rule;
    return i;
  }

  [[noreturn]] void Fail(const Field& f, const S& options, const std::string& rule) const {
    SAMP_THROW() << struct_name_ << "." << f.info.name << " must be " << rule << ", got "
                 << f.text(options);
  }

  static bool IsChoice(const OptionInfo& info, const std::string& value) {
    if (info.empty_choice && value.empty()) return true;
    for (const std::string& s : info.choices) {
      if (s == value) return true;
    }
    return false;
  }
  static std::string ChoicesText(const OptionInfo& info) {
    std::string text = info.empty_choice ? "empty or one of " : "one of ";
    for (size_t k = 0; k < info.choices.size(); ++k) text += (k ? ", " : "") + info.choices[k];
    return text;
  }

  static std::string ValueText(bool v) { return v ? "true" : "false"; }
  static std::string ValueText(int v) { return std::to_string(v); }
  static std::string ValueText(std::uint64_t v) { return std::to_string(v); }
  static std::string ValueText(double v) { return FormatOptionNumber(v); }
  static std::string ValueText(const std::string& v) { return v; }

  template <typename T>
  static T ParseValue(const std::string& text);

  // The JSON of one field (or of a nested struct: kNoField), in the table's order.
  static constexpr size_t kNoField = size_t(-1);
  struct JsonVisit {
    size_t field;
    std::function<void(OptionsJson&, S&)> visit;
  };

  void RemoveJson(size_t field) {
    json_.erase(std::remove_if(json_.begin(), json_.end(), [field](const JsonVisit& j) { return j.field == field; }),
                json_.end());
  }
  void DefaultWhenAbsent(size_t field) {
    for (JsonVisit& j : json_) {
      if (j.field != field) continue;
      j.visit = [visit = j.visit, name = fields_[field].info.name, copy = fields_[field].copy](OptionsJson& io,
                                                                                               S& s) {
        if (io.writing() || io.Has(name)) return visit(io, s);
        const auto defaults = std::make_unique<const S>();
        copy(*defaults, &s);
      };
    }
  }

  static std::vector<double> ListNumbers(const std::vector<double>& v) { return v; }
  static std::vector<double> ListNumbers(const std::vector<Eigen::Vector3d>& v) {
    std::vector<double> numbers;
    for (const Eigen::Vector3d& x : v) numbers.insert(numbers.end(), {x.x(), x.y(), x.z()});
    return numbers;
  }
  static std::string ListText(const std::vector<std::string>& v) { return JoinOptionList(v); }
  template <typename E>
  static std::string ListText(const std::vector<E>& v) {
    std::vector<std::string> texts;
    for (double x : ListNumbers(v)) texts.push_back(FormatOptionNumber(x));
    return JoinOptionList(texts);
  }
  template <typename E>
  static std::vector<E> ParseList(const std::string& name, const std::vector<std::string>& values) {
    if constexpr (std::is_same_v<E, std::string>) {
      return values;
    } else if constexpr (std::is_same_v<E, double>) {
      std::vector<double> numbers;
      for (const std::string& v : values) numbers.push_back(ParseOptionDouble(v));
      return numbers;
    } else {
      SAMP_CHECK(values.size() % 3 == 0) << name << ": 3 numbers a value, got " << values.size();
      std::vector<Eigen::Vector3d> items;
      for (size_t k = 0; k < values.size(); k += 3) {
        items.emplace_back(ParseOptionDouble(values[k]), ParseOptionDouble(values[k + 1]),
                           ParseOptionDouble(values[k + 2]));
      }
      return items;
    }
  }
  template <typename E>
  static void ListJson(OptionsJson& io, const std::string& name, std::vector<E>& v) {
    if constexpr (std::is_same_v<E, Eigen::Vector3d>) {
      std::vector<std::array<double, 3>> items;
      for (const Eigen::Vector3d& x : v) items.push_back({x.x(), x.y(), x.z()});
      io(name, items);
      if (io.writing()) return;
      v.clear();
      for (const auto& x : items) v.emplace_back(x[0], x[1], x[2]);
    } else {
      io(name, v);
    }
  }

  std::string struct_name_;
  std::vector<Field> fields_;
  std::vector<JsonVisit> json_;
};

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
