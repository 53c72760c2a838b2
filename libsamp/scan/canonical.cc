#include "libsamp/core/json_text.h"
#include "libsamp/scan/canonical.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "libsamp/core/error.h"
#include "libsamp/scan/mesh_io.h"

namespace samp {
namespace {

// Two extents closer than this (relative to the larger) are called ambiguous.
constexpr double kAmbiguityRatio = 0.10;

struct Axis {
  int index = 0;  // 0 = x, 1 = y, 2 = z
  int sign = 1;   // +1 or -1
  Eigen::Vector3d Direction() const { return sign * Eigen::Vector3d::Unit(index); }
};

bool IsAxisName(const std::string& name) {
  return name.size() == 2 && (name[0] == '+' || name[0] == '-') &&
         (name[1] == 'x' || name[1] == 'y' || name[1] == 'z');
}

Axis ParseAxis(const std::string& name) {
  Axis axis;
  axis.sign = name[0] == '-' ? -1 : 1;
  axis.index = name[1] - 'x';
  return axis;
}

std::string AxisName(const Axis& axis) {
  return std::string(axis.sign < 0 ? "-" : "+") + char('x' + axis.index);
}

std::string FormatSize(const Eigen::Vector3d& size) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(3) << "length " << size.x() << " m, height " << size.y()
      << " m, width " << size.z() << " m";
  return out.str();
}

bool Ambiguous(double a, double b) {
  return std::abs(a - b) <= kAmbiguityRatio * std::max(std::abs(a), std::abs(b));
}

}  // namespace

void CanonicalizeOptions::Check() const {
  SAMP_CHECK(!(scale && target_length))
      << "canonicalize: scale and target_length are exclusive; give at most one";
  SAMP_CHECK(!scale || (std::isfinite(*scale) && *scale > 0))
      << "canonicalize: scale must be a positive number, got " << *scale;
  SAMP_CHECK(!target_length || (std::isfinite(*target_length) && *target_length > 0))
      << "canonicalize: target_length must be a positive number of metres, got "
      << *target_length;
  SAMP_CHECK(up == "auto" || IsAxisName(up))
      << "canonicalize: up must be one of +x -x +y -y +z -z auto, got '" << up << "'";
  SAMP_CHECK(forward == "auto" || IsAxisName(forward))
      << "canonicalize: forward must be one of +x -x +y -y +z -z auto, got '" << forward << "'";
  SAMP_CHECK(up == "auto" || forward == "auto" || up[1] != forward[1])
      << "canonicalize: up (" << up << ") and forward (" << forward
      << ") must be different axes";
  SAMP_CHECK(min_size.allFinite() && max_size.allFinite() && (min_size.array() >= 0).all() &&
             (min_size.array() <= max_size.array()).all())
      << "canonicalize: need 0 <= min_size <= max_size per component";
  if (add_wheels) wheels.Check();
}

CanonicalizeOptions CanonicalPreset(const std::string& name) {
  CanonicalizeOptions options;
  if (name == "shapenet") {
    options.up = "+y";
    options.forward = "-z";
    options.scale = 4.49;
  } else if (name == "apollocar3d") {
    options.up = "-y";
    options.forward = "+z";
    options.scale = 1.0;
  } else {
    std::string known;
    for (const std::string& n : CanonicalPresetNames()) known += (known.empty() ? "" : ", ") + n;
    SAMP_THROW() << "unknown canonicalisation preset '" << name << "' (known: " << known << ")";
  }
  return options;
}

std::vector<std::string> CanonicalPresetNames() { return {"shapenet", "apollocar3d"}; }

CanonicalizeResult Canonicalize(const Mesh& cad_mesh, const CanonicalizeOptions& options) {
  options.Check();
  SAMP_CHECK(!cad_mesh.Empty()) << "canonicalize: the mesh is empty";
  const AlignedBox cad_box = cad_mesh.Bounds();
  SAMP_CHECK(!cad_box.IsEmpty() && cad_box.min.allFinite() && cad_box.max.allFinite())
      << "canonicalize: the mesh has no finite bounding box";
  const Eigen::Vector3d extent = cad_box.Size();
  SAMP_CHECK(extent.maxCoeff() > 0) << "canonicalize: the mesh has zero extent";

  CanonicalizeResult result;
  // --- Axes. ---
  // forward: given, or the longest extent among the axes that are not `up`.
  // up: given, or the smaller extent among the two axes that are not `forward`.
  // A sign that auto-detection cannot know is taken as '+', with a warning.
  std::optional<Axis> up, forward;
  if (options.up != "auto") up = ParseAxis(options.up);
  if (options.forward != "auto") forward = ParseAxis(options.forward);
  if (!forward) {
    // Candidates: every axis but `up` (all three when up is unknown as well).
    int best = -1, second = -1;
    for (int i = 0; i < 3; ++i) {
      if (up && up->index == i) continue;
      if (best < 0 || extent[i] > extent[best]) {
        second = best;
        best = i;
      } else if (second < 0 || extent[i] > extent[second]) {
        second = i;
      }
    }
    forward = Axis{best, +1};
    std::ostringstream warning;
    warning << "forward axis auto-detected as the longest " << (up ? "horizontal " : "")
            << "extent, CAD " << char('x' + best)
            << "; its sign cannot be told from the bounding box, assumed +" << char('x' + best);
    if (Ambiguous(extent[best], extent[second])) {
      warning << " (ambiguous: extents along " << char('x' + best) << " and " << char('x' + second)
              << " differ by less than " << int(kAmbiguityRatio * 100) << " %)";
    }
    result.warnings.push_back(warning.str());
  }
  if (!up) {
    const int a = (forward->index + 1) % 3, b = (forward->index + 2) % 3;
    const int height_axis = extent[a] <= extent[b] ? a : b;
    const int width_axis = height_axis == a ? b : a;
    up = Axis{height_axis, +1};
    std::ostringstream warning;
    warning << "up axis auto-detected as the smaller of the two non-length extents, CAD "
            << char('x' + height_axis) << "; its sign cannot be told from the bounding box, assumed +"
            << char('x' + height_axis);
    if (Ambiguous(extent[height_axis], extent[width_axis])) {
      warning << " (ambiguous: extents along " << char('x' + height_axis) << " and "
              << char('x' + width_axis) << " differ by less than " << int(kAmbiguityRatio * 100)
              << " %)";
    }
    result.warnings.push_back(warning.str());
  }
  SAMP_CHECK(up->index != forward->index) << "canonicalize: up and forward are the same axis";
  result.up = AxisName(*up);
  result.forward = AxisName(*forward);

  // Rows of the rotation: canonical x = forward, y = down = -up, z = x cross y.
  const Eigen::Vector3d x_axis = forward->Direction();
  const Eigen::Vector3d y_axis = -up->Direction();
  const Eigen::Vector3d z_axis = x_axis.cross(y_axis);
  Eigen::Matrix3d object_from_cad_rotation;
  object_from_cad_rotation.row(0) = x_axis.transpose();
  object_from_cad_rotation.row(1) = y_axis.transpose();
  object_from_cad_rotation.row(2) = z_axis.transpose();

  // --- Scale. ---
  if (options.scale) {
    result.scale = *options.scale;
  } else if (options.target_length) {
    result.scale = *options.target_length / extent[forward->index];
  } else {
    result.scale = 1.0;  // CAD units are taken as metres
  }

  // --- Translation: the centre of the bottom face (max y, since y points down) to the origin. ---
  const Eigen::Matrix3d linear = result.scale * object_from_cad_rotation;
  AlignedBox box;
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d corner((k & 1) ? cad_box.max.x() : cad_box.min.x(),
                                 (k & 2) ? cad_box.max.y() : cad_box.min.y(),
                                 (k & 4) ? cad_box.max.z() : cad_box.min.z());
    box.Extend(linear * corner);
  }
  const Eigen::Vector3d bottom_centre(box.Center().x(), box.max.y(), box.Center().z());
  result.object_from_cad.linear() = linear;
  result.object_from_cad.translation() = -bottom_centre;
  result.object_from_cad.makeAffine();
  result.size = box.Size();

  const bool plausible = (result.size.array() >= options.min_size.array()).all() &&
                         (result.size.array() <= options.max_size.array()).all();
  SAMP_CHECK(plausible) << "implausible size after canonicalisation: " << FormatSize(result.size)
                        << " (scale " << result.scale << ", up " << result.up << ", forward "
                        << result.forward << "); plausible range " << FormatSize(options.min_size)
                        << " to " << FormatSize(options.max_size)
                        << " -- check the scale/units and axes";

  result.mesh = cad_mesh;
  result.mesh.Transform(result.object_from_cad);
  if (options.add_wheels) {
    WheeledCar car = AddWheels(result.mesh, options.wheels);
    result.wheels = car.placement;
    result.wheels_added = true;
    result.mesh = car.Combined();
    result.object_from_cad.pretranslate(Eigen::Vector3d(0.0, -car.placement.lift, 0.0));
    result.size = result.mesh.Bounds().Size();
  }
  return result;
}

// ---------------------------------------------------------------------------
// Manifest.

namespace {

using Json = nlohmann::json;

class ManifestParser {
 public:
  explicit ManifestParser(std::string path) : path_(std::move(path)) {}

  [[noreturn]] void Fail(const std::string& field, const std::string& message) const {
    SAMP_THROW() << "manifest '" << path_ << "': " << field << ": " << message;
  }

  double PositiveNumber(const Json& value, const std::string& field) const {
    if (!value.is_number()) Fail(field, "expected a number, got " + DumpJson(value));
    const double number = value.get<double>();
    if (!(std::isfinite(number) && number > 0)) Fail(field, "expected a positive number");
    return number;
  }

  std::string String(const Json& value, const std::string& field) const {
    if (!value.is_string()) Fail(field, "expected a string, got " + DumpJson(value));
    return value.get<std::string>();
  }

  std::string AxisString(const Json& value, const std::string& field) const {
    const std::string axis = String(value, field);
    if (axis != "auto" && !IsAxisName(axis)) {
      Fail(field, "expected one of \"+x\" \"-x\" \"+y\" \"-y\" \"+z\" \"-z\" \"auto\", got \"" + axis +
                      "\"");
    }
    return axis;
  }

  Eigen::Vector3d Vector3(const Json& value, const std::string& field) const {
    if (!value.is_array() || value.size() != 3) {
      Fail(field, "expected an array of 3 numbers [length, height, width], got " + DumpJson(value));
    }
    Eigen::Vector3d v;
    for (int i = 0; i < 3; ++i) {
      if (!value[i].is_number()) Fail(field, "expected numbers, got " + DumpJson(value));
      v[i] = value[i].get<double>();
    }
    return v;
  }

  // Applies the canonicalisation keys of `object` onto `options`; returns false
  // for keys it does not know (so that the caller can handle or reject them).
  bool CanonicalizeKey(const std::string& key, const Json& value, const std::string& field,
                       CanonicalizeOptions* options) const {
    if (key == "scale") {
      options->scale = PositiveNumber(value, field);
      options->target_length.reset();
    } else if (key == "target_length") {
      options->target_length = PositiveNumber(value, field);
      options->scale.reset();
    } else if (key == "up") {
      options->up = AxisString(value, field);
    } else if (key == "forward") {
      options->forward = AxisString(value, field);
    } else if (key == "min_size") {
      options->min_size = Vector3(value, field);
    } else if (key == "max_size") {
      options->max_size = Vector3(value, field);
    } else if (key == "wheels") {
      const std::string wheels = String(value, field);
      if (wheels != "synthesise" && wheels != "mesh") {
        Fail(field, "expected \"synthesise\" (add tyres under a body without wheels) or \"mesh\", got \"" +
                        wheels + "\"");
      }
      options->add_wheels = wheels == "synthesise";
    } else if (key == "ground_clearance") {
      if (!value.is_number() || !(value.get<double>() >= 0.0) || !std::isfinite(value.get<double>())) {
        Fail(field, "expected a number >= 0 (metres), got " + DumpJson(value));
      }
      options->wheels.ground_clearance = value.get<double>();
    } else if (key == "wheel_radius") {
      options->wheels.radius = PositiveNumber(value, field);
    } else {
      return false;
    }
    return true;
  }

  void CheckOptions(const CanonicalizeOptions& options, const std::string& field) const {
    try {
      options.Check();
    } catch (const Error& e) {
      Fail(field, e.what());
    }
  }

  Manifest Parse(const Json& root) const {
    if (!root.is_object()) Fail("(top level)", "expected a JSON object");
    Manifest manifest;
    // Defaults first, so that entries inherit them whatever the key order.
    if (root.contains("defaults")) {
      const Json& defaults = root["defaults"];
      if (!defaults.is_object()) Fail("defaults", "expected an object");
      if (defaults.contains("scale") && defaults.contains("target_length")) {
        Fail("defaults", "give scale or target_length, not both");
      }
      for (const auto& [key, value] : defaults.items()) {
        const std::string field = "defaults." + key;
        if (key == "comment") {
          String(value, field);
        } else if (!CanonicalizeKey(key, value, field, &manifest.defaults)) {
          Fail(field, "unknown key (known: scale, target_length, up, forward, min_size, "
                      "max_size, wheels, ground_clearance, wheel_radius, comment)");
        }
      }
      CheckOptions(manifest.defaults, "defaults");
    }
    for (const auto& [key, value] : root.items()) {
      if (key == "defaults") continue;
      if (key == "comment") {
        String(value, key);
      } else if (key == "models") {
        if (!value.is_array()) Fail("models", "expected an array");
        for (size_t i = 0; i < value.size(); ++i) {
          manifest.entries.push_back(ParseEntry(value[i], "models[" + std::to_string(i) + "]",
                                                manifest.defaults));
        }
      } else {
        Fail(key, "unknown key (known: defaults, models, comment)");
      }
    }
    std::set<std::string> files, names;
    for (size_t i = 0; i < manifest.entries.size(); ++i) {
      const ManifestEntry& entry = manifest.entries[i];
      const std::string field = "models[" + std::to_string(i) + "]";
      if (!files.insert(entry.file).second) Fail(field + ".file", "duplicate file \"" + entry.file + "\"");
      if (!names.insert(entry.name).second) Fail(field + ".name", "duplicate name \"" + entry.name + "\"");
    }
    return manifest;
  }

  ManifestEntry ParseEntry(const Json& object, const std::string& prefix,
                           const CanonicalizeOptions& defaults) const {
    if (!object.is_object()) Fail(prefix, "expected an object");
    ManifestEntry entry;
    entry.canonicalize = defaults;
    if (!object.contains("file")) Fail(prefix + ".file", "missing (required)");
    // A model that gives scale overrides a default target_length and vice versa;
    // giving both in one model is an error.
    if (object.contains("scale") && object.contains("target_length")) {
      Fail(prefix, "give scale or target_length, not both");
    }
    for (const auto& [key, value] : object.items()) {
      const std::string field = prefix + "." + key;
      if (key == "file") {
        entry.file = String(value, field);
        if (entry.file.empty()) Fail(field, "must not be empty");
      } else if (key == "name") {
        entry.name = String(value, field);
        if (entry.name.empty()) Fail(field, "must not be empty");
      } else if (key == "skip") {
        if (!value.is_boolean()) Fail(field, "expected true or false, got " + DumpJson(value));
        entry.skip = value.get<bool>();
      } else if (key == "skip_reason") {
        entry.skip_reason = String(value, field);
      } else if (key == "comment") {
        String(value, field);
      } else if (!CanonicalizeKey(key, value, field, &entry.canonicalize)) {
        Fail(field, "unknown key (known: file, name, scale, target_length, up, forward, "
                    "min_size, max_size, wheels, ground_clearance, wheel_radius, skip, skip_reason, comment)");
      }
    }
    if (entry.name.empty()) entry.name = std::filesystem::path(entry.file).stem().string();
    CheckOptions(entry.canonicalize, prefix);
    return entry;
  }

 private:
  std::string path_;
};

std::string NormalizedRelative(const std::string& path) {
  return std::filesystem::path(path).lexically_normal().generic_string();
}

}  // namespace

const ManifestEntry* Manifest::Find(const std::string& relative_path) const {
  const std::string wanted = NormalizedRelative(relative_path);
  for (const ManifestEntry& entry : entries) {
    if (NormalizedRelative(entry.file) == wanted) return &entry;
  }
  // Fall back to the file name alone, when exactly one entry has it.
  const std::string file_name = std::filesystem::path(wanted).filename().string();
  const ManifestEntry* found = nullptr;
  for (const ManifestEntry& entry : entries) {
    if (std::filesystem::path(entry.file).filename().string() == file_name) {
      if (found != nullptr) return nullptr;
      found = &entry;
    }
  }
  return found;
}

std::vector<CadFile> ListCadFiles(const std::string& folder, const Manifest* manifest) {
  std::vector<CadFile> files;
  for (const std::string& path : ListMeshFiles(folder)) {
    CadFile file;
    file.path = path;
    file.relative_path = std::filesystem::path(path).lexically_relative(folder).generic_string();
    file.entry = manifest != nullptr ? manifest->Find(file.relative_path) : nullptr;
    const bool named = file.entry != nullptr && !file.entry->name.empty();
    file.name = named ? file.entry->name : std::filesystem::path(path).stem().string();
    if (file.entry != nullptr) {
      file.canonicalize = file.entry->canonicalize;
    } else if (manifest != nullptr) {
      file.canonicalize = manifest->defaults;
    }
    files.push_back(std::move(file));
  }
  std::sort(files.begin(), files.end(),
            [](const CadFile& a, const CadFile& b) { return a.relative_path < b.relative_path; });
  return files;
}

Manifest LoadManifest(const std::string& path) {
  std::ifstream in(path);
  SAMP_CHECK(in) << "cannot open manifest '" << path << "'";
  Json root;
  try {
    root = Json::parse(in);
  } catch (const Json::exception& e) {
    SAMP_THROW() << "manifest '" << path << "' is not valid JSON: " << e.what();
  }
  return ManifestParser(path).Parse(root);
}

}  // namespace samp
