#include "libsamp/core/json_fields.h"

#include <fstream>
#include <sstream>

namespace samp {

nlohmann::json ReadJsonFile(const std::string& path) {
  std::ifstream in(path);
  SAMP_CHECK(in.good()) << "cannot read " << path;
  std::ostringstream text;
  text << in.rdbuf();
  return ParseJson(text.str(), path);
}

nlohmann::json ParseJson(const std::string& text, const std::string& source) {
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    SAMP_THROW() << "cannot parse " << source << " as JSON: " << e.what();
  }
}

JsonFields::JsonFields(const nlohmann::json& object, std::string source, std::string path)
    : object_(&object), source_(std::move(source)), path_(std::move(path)) {
  SAMP_CHECK(object.is_object()) << Where() << ": expected a JSON object, got " << object.type_name();
}

std::string JsonFields::Where() const { return path_.empty() ? source_ : source_ + ": " + path_; }

const nlohmann::json& JsonFields::At(const std::string& key) const {
  const auto it = object_->find(key);
  SAMP_CHECK(it != object_->end()) << Where() << ": missing key '" << key << "'";
  return *it;
}

JsonFields JsonFields::Object(const std::string& key) const {
  return JsonFields(At(key), source_, path_.empty() ? key : path_ + "." + key);
}

std::vector<JsonFields> JsonFields::Objects(const std::string& key) const {
  const nlohmann::json& array = At(key);
  SAMP_CHECK(array.is_array()) << Where() << ": key '" << key << "' must be an array, got "
                               << array.type_name();
  std::vector<JsonFields> objects;
  const std::string prefix = path_.empty() ? key : path_ + "." + key;
  for (size_t i = 0; i < array.size(); ++i)
    objects.emplace_back(array[i], source_, prefix + "[" + std::to_string(i) + "]");
  return objects;
}

}  // namespace samp
