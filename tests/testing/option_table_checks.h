// Checks every option table passes (core/option_table.h), shared by the tests
// of the layers that declare one: each field is wired to its own member (JSON
// and command line), the JSON round-trips, and a doc's option list is the
// table's.
#pragma once

#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <map>
#include <set>
#include <sstream>
#include <string>

#include "libsamp/core/option_table.h"

namespace samp::test {

// A list other than the default, as ","-separated text (OptionBinding::set).
inline std::string OtherList(const OptionInfo& info) {
  if (info.kind == OptionKind::kText) return info.default_text.empty() ? "other" : info.default_text + ",other";
  for (double value : {1.0, 0.75, 2.0, 10.0}) {
    const std::string text = FormatOptionNumber(value);
    if (!info.Validate(text).empty()) continue;
    std::string list;
    for (int k = 0; k < info.arity; ++k) list += (k ? "," : "") + text;
    if (list != info.default_text) return list;
  }
  ADD_FAILURE() << info.name << ": no other value";
  return info.default_text;
}

// A value other than the default, as command-line text.
inline std::string OtherValue(const OptionInfo& info) {
  if (info.list) return OtherList(info);
  switch (info.kind) {
    case OptionKind::kFlag:
      return info.default_text == "true" ? "false" : "true";
    case OptionKind::kInt: {
      // The first of a few others that the field's own rule admits.
      const int value = std::stoi(info.default_text);
      for (int other : {value + 7, value + 2, value - 2, value - 7, value + 1, value - 1}) {
        if (info.Validate(std::to_string(other)).empty()) return std::to_string(other);
      }
      break;
    }
    case OptionKind::kUnsigned:
      return std::to_string(std::stoull(info.default_text) + 7);
    case OptionKind::kNumber: {
      // The first of a few others that the field's own rule admits.
      const double value = std::stod(info.default_text);
      for (double other : {value != 0.0 ? value * 0.75 : 0.25, value * 1.25, value + 1.0, value - 0.5}) {
        const std::string text = FormatOptionNumber(other);
        if (other != value && info.Validate(text).empty()) return text;
      }
      break;
    }
    case OptionKind::kText:
    case OptionKind::kChoice:
      if (info.choices.empty()) return info.default_text + "other";
      for (const std::string& c : info.choices) {
        if (c != info.default_text) return c;
      }
  }
  ADD_FAILURE() << info.name << ": no other value";
  return info.default_text;
}

// The JSON leaves of `j` as "a.b" -> value text.
inline void JsonLeaves(const nlohmann::json& j, const std::string& prefix, std::map<std::string, std::string>* out) {
  for (auto it = j.begin(); it != j.end(); ++it) {
    if (it->is_object()) {
      JsonLeaves(*it, prefix + it.key() + ".", out);
    } else {
      (*out)[prefix + it.key()] = it->dump();
    }
  }
}

// The JSON leaves of the options `o` but those under `nested` ("fit." for a
// struct whose JSON nests others besides its table's fields).
template <typename S>
std::map<std::string, std::string> TableLeaves(const S& o, const std::vector<std::string>& nested) {
  std::map<std::string, std::string> leaves;
  JsonLeaves(OptionsToJson(o), "", &leaves);
  for (auto it = leaves.begin(); it != leaves.end();) {
    bool skip = false;
    for (const std::string& n : nested) skip = skip || it->first.rfind(n, 0) == 0;
    it = skip ? leaves.erase(it) : std::next(it);
  }
  return leaves;
}

// The JSON (OptionsToJson) holds exactly the table's fields (but those marked
// NotInJson, and the structs nested under `nested`), each once, with
// distinct command-line names; setting one field through its binding (a
// valid other value) changes that JSON key and no other.
template <typename S>
void ExpectEveryFieldWired(const OptionTable<S>& table, const std::string& prefix,
                           const std::vector<std::string>& nested = {}) {
  const std::vector<OptionInfo> infos = table.Describe();
  std::map<std::string, std::string> defaults = TableLeaves(S(), nested);
  std::set<std::string> optional;
  // Fields written only when they differ from their default (AddOptional)
  // are absent from the defaults' JSON: they count once set below.
  for (const OptionInfo& i : infos) {
    if (defaults.count(i.name) || !i.in_json) continue;
    S changed;
    for (const OptionBinding& b : table.Bind(&changed)) {
      if (b.info.name != i.name) continue;
      if (b.info.kind == OptionKind::kFlag) {
        *b.flag = !*b.flag;
      } else {
        b.set(OtherValue(i));
      }
    }
    if (TableLeaves(changed, nested).count(i.name)) {
      defaults[i.name] = "(written when set)";
      optional.insert(i.name);
    }
  }
  std::set<std::string> names, flags;
  size_t in_json = 0;
  for (const OptionInfo& i : infos) {
    EXPECT_TRUE(names.insert(i.name).second) << i.name;
    in_json += i.in_json ? 1 : 0;
    EXPECT_EQ(defaults.count(i.name), i.in_json ? 1u : 0u) << i.name << (i.in_json ? " not" : "") << " in the JSON";
    EXPECT_FALSE(i.help.empty()) << i.name;
    if (i.internal) continue;
    EXPECT_TRUE(flags.insert(CommandLineName(i, prefix)).second) << i.flag;
    if (i.kind == OptionKind::kFlag && i.flag_names != FlagNames::kOnOnly) {
      EXPECT_TRUE(flags.insert(OffFlagName(i, prefix)).second) << i.name;
    }
    for (const auto& d : i.deprecated) EXPECT_TRUE(flags.insert(CommandLineName(d.first, prefix)).second) << d.first;
  }
  EXPECT_EQ(in_json, defaults.size());
  for (const OptionInfo& info : infos) {
    if (!info.in_json) continue;
    S options;
    for (const OptionBinding& b : table.Bind(&options)) {
      if (b.info.name != info.name) continue;
      const std::string value = OtherValue(info);
      for (const std::string& part : info.list ? SplitOptionList(value) : std::vector<std::string>{value}) {
        EXPECT_EQ(b.info.Validate(part), "") << info.name << " = " << value;
      }
      b.set(value);
    }
    std::map<std::string, std::string> changed = TableLeaves(options, nested);
    for (const auto& [key, text] : defaults) {
      // An optional field at its default is absent, which is its default.
      const std::string now = changed.count(key) || !optional.count(key) ? changed[key] : text;
      EXPECT_EQ(now != text, key == info.name) << "setting " << info.name << ": " << key;
    }
  }
}

// Every field set to another value is read back from its JSON.
template <typename S>
void ExpectJsonRoundTrip(const OptionTable<S>& table) {
  S options;
  for (const OptionBinding& b : table.Bind(&options)) b.set(OtherValue(b.info));
  const nlohmann::json written = OptionsToJson(options);
  S read;
  OptionsFromJson(JsonFields(written, "config.json"), &read);
  EXPECT_EQ(OptionsToJson(read), written);
  EXPECT_NE(written, OptionsToJson(S()));
}

// The text of `path` between "<!-- begin: MARKER -->\n" and "<!-- end: MARKER -->".
inline std::string DocSection(const std::string& path, const std::string& marker) {
  std::ifstream in(path);
  EXPECT_TRUE(in.good()) << path;
  std::stringstream text;
  text << in.rdbuf();
  const std::string doc = text.str();
  const std::string begin = "<!-- begin: " + marker + " -->\n", end = "<!-- end: " + marker + " -->";
  const size_t a = doc.find(begin), b = doc.find(end);
  if (a == std::string::npos || b == std::string::npos || b < a) {
    ADD_FAILURE() << path << ": no section between the markers '" << marker << "'";
    return "";
  }
  return doc.substr(a + begin.size(), b - a - begin.size());
}

}  // namespace samp::test
