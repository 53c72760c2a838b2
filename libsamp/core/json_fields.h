// Strict reading of the JSON files samp writes (tracks.json, config.json, the
// trainer options in a model file): a missing key or a value of the wrong type
// is a samp::Error naming the file and the key path ("tracks.json:
// sequences[0].tracks[2].frames[4]: missing key 'yaw'"). No silent defaults.
// A JsonFields refers to the json it was made from (which must outlive it).
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "libsamp/core/json_text.h"
#include "libsamp/core/error.h"

namespace samp {

// Parses a JSON file; throws samp::Error naming the file when it is missing or malformed.
nlohmann::json ReadJsonFile(const std::string& path);
// Parses JSON text; `source` names it in errors (a file, "model metadata of X").
nlohmann::json ParseJson(const std::string& text, const std::string& source);

class JsonFields {
 public:
  // `object` must be a JSON object (else throws naming `source` and `path`).
  JsonFields(const nlohmann::json& object, std::string source, std::string path = "");

  bool Has(const std::string& key) const { return object_->contains(key); }
  // The value at `key`; throws when the key is missing.
  const nlohmann::json& At(const std::string& key) const;
  // The value at `key` converted to T; throws when missing or of another type.
  template <typename T>
  T Get(const std::string& key) const {
    const nlohmann::json& value = At(key);
    try {
      return value.get<T>();
    } catch (const nlohmann::json::exception&) {
      SAMP_THROW() << Where() << ": key '" << key << "' has the wrong type (" << value.type_name() << ": "
                   << DumpJson(value) << ")";
    }
  }
  template <typename T>
  void Read(const std::string& key, T* value) const {
    *value = Get<T>(key);
  }
  // The object at `key`.
  JsonFields Object(const std::string& key) const;
  // The objects of the array at `key`.
  std::vector<JsonFields> Objects(const std::string& key) const;

  const std::string& source() const { return source_; }
  // "source: path" (or "source" at the top level).
  std::string Where() const;

 private:
  const nlohmann::json* object_;
  std::string source_;
  std::string path_;
};

// One function per options struct lists its fields once, for both directions:
//   void OptionFields(OptionsJson& io, StereoOptions& o) {
//     io("min_disparity", o.min_disparity);
//     io.Nested("noise", o.noise);   // calls OptionFields(io', o.noise)
//   }
// OptionsToJson(o) writes every field (the effective options of a run, for
// its config.json; an Optional field only when it differs from its default,
// or always with JsonDefaults::kWrite); OptionsFromJson(fields, &o) reads
// every field back and throws naming the file and key when one is missing.
// Whether a writer also writes the Optional fields that keep their default
// (kOmit: files keep their bytes; kWrite: the whole struct, e.g. for an API
// that lists every field).
enum class JsonDefaults { kOmit, kWrite };

class OptionsJson {
 public:
  explicit OptionsJson(nlohmann::json* out, JsonDefaults defaults = JsonDefaults::kOmit)
      : out_(out), defaults_(defaults) {}
  explicit OptionsJson(const JsonFields* in) : in_(in) {}

  bool writing() const { return out_ != nullptr; }
  // Reading: whether the JSON holds `key`.
  bool Has(const std::string& key) const { return in_ != nullptr && in_->Has(key); }

  template <typename T>
  void operator()(const std::string& key, T& value) {
    if (writing()) {
      (*out_)[key] = value;
    } else {
      in_->Read(key, &value);
    }
  }
  // A field added after the format settled: written only when it differs from
  // `default_value` (outputs of runs that do not use it stay as they were),
  // read when present and `default_value` otherwise.
  template <typename T>
  void Optional(const std::string& key, T& value, const T& default_value) {
    if (writing()) {
      if (write_defaults() || !(value == default_value)) (*out_)[key] = value;
    } else {
      value = in_->Has(key) ? in_->Get<T>(key) : default_value;
    }
  }
  // An enum written by its name: to_name(value) -> const char*, from_name(std::string) -> E
  // (throws for an unknown name; the error is given the file and key).
  template <typename E, typename ToName, typename FromName>
  void Named(const std::string& key, E& value, ToName to_name, FromName from_name) {
    if (writing()) {
      (*out_)[key] = std::string(to_name(value));
    } else {
      const std::string name = in_->Get<std::string>(key);
      try {
        value = from_name(name);
      } catch (const std::exception& e) {
        SAMP_THROW() << in_->Where() << ": key '" << key << "': " << e.what();
      }
    }
  }
  // Named, written only when it differs from `default_value` (as Optional).
  template <typename E, typename ToName, typename FromName>
  void OptionalNamed(const std::string& key, E& value, const E& default_value, ToName to_name, FromName from_name) {
    if (writing()) {
      if (write_defaults() || !(value == default_value)) Named(key, value, to_name, from_name);
    } else if (in_->Has(key)) {
      Named(key, value, to_name, from_name);
    } else {
      value = default_value;
    }
  }
  template <typename S>
  void Nested(const std::string& key, S& options) {
    NestedWith(key, [&options](OptionsJson& io) { OptionFields(io, options); });
  }
  // Nested, written only when it differs from a default-constructed S (as
  // Optional: outputs of runs that keep the defaults stay as they were); read
  // when present, S{} otherwise.
  template <typename S>
  void OptionalNested(const std::string& key, S& options) {
    if (writing()) {
      nlohmann::json child = nlohmann::json::object();
      nlohmann::json defaults = nlohmann::json::object();
      OptionsJson child_io(&child, defaults_);
      OptionFields(child_io, options);
      S default_options{};
      OptionsJson defaults_io(&defaults, defaults_);
      OptionFields(defaults_io, default_options);
      if (write_defaults() || child != defaults) (*out_)[key] = std::move(child);
    } else if (in_->Has(key)) {
      Nested(key, options);
    } else {
      options = S{};
    }
  }
  // An array of objects at `key`, the fields of each listed by OptionFields(io, S&).
  template <typename S>
  void Array(const std::string& key, std::vector<S>& items) {
    if (writing()) {
      nlohmann::json array = nlohmann::json::array();
      for (S& item : items) {
        nlohmann::json child = nlohmann::json::object();
        OptionsJson io(&child, defaults_);
        OptionFields(io, item);
        array.push_back(std::move(child));
      }
      (*out_)[key] = std::move(array);
    } else {
      items.clear();
      for (const JsonFields& child : in_->Objects(key)) {
        S item;
        OptionsJson io(&child);
        OptionFields(io, item);
        items.push_back(std::move(item));
      }
    }
  }
  // The object at `key`, its fields listed by visit(OptionsJson&) (an OptionTable's Json).
  template <typename Visit>
  void NestedWith(const std::string& key, Visit visit) {
    if (writing()) {
      nlohmann::json child = nlohmann::json::object();
      OptionsJson io(&child, defaults_);
      visit(io);
      (*out_)[key] = std::move(child);
    } else {
      const JsonFields child = in_->Object(key);
      OptionsJson io(&child);
      visit(io);
    }
  }

 private:
  bool write_defaults() const { return defaults_ == JsonDefaults::kWrite; }

  nlohmann::json* out_ = nullptr;
  const JsonFields* in_ = nullptr;
  JsonDefaults defaults_ = JsonDefaults::kOmit;
};

template <typename S>
nlohmann::json OptionsToJson(const S& options, JsonDefaults defaults = JsonDefaults::kOmit) {
  nlohmann::json j = nlohmann::json::object();
  OptionsJson io(&j, defaults);
  OptionFields(io, const_cast<S&>(options));  // the writer only reads the fields
  return j;
}

template <typename S>
void OptionsFromJson(const JsonFields& fields, S* options) {
  OptionsJson io(&fields);
  OptionFields(io, *options);
}

}  // namespace samp
