#include "libsamp/data/detection_files.h"

#include <cmath>
#include <iomanip>
#include <sstream>

#include "libsamp/core/atomic_file.h"
#include "libsamp/core/error.h"
#include "libsamp/data/kitti_io.h"
#include "libsamp/data/kitti_text.h"

namespace samp {
using namespace kitti_text;

namespace {

// AB3DMOT's class ids (its KITTI data: 1 pedestrian, 2 car, 3 cyclist).
const char* Ab3dmotTypeName(int id) {
  switch (id) {
    case 1: return "Pedestrian";
    case 2: return "Car";
    case 3: return "Cyclist";
    default: return nullptr;
  }
}

int Ab3dmotTypeId(const std::string& type) {
  for (int id = 1; id <= 3; ++id)
    if (SameObjectType(type, Ab3dmotTypeName(id))) return id;
  return 0;
}

std::vector<std::string> SplitCommas(const std::string& line) {
  std::vector<std::string> fields;
  std::stringstream stream(line);
  for (std::string field; std::getline(stream, field, ',');) {
    field.erase(0, field.find_first_not_of(" \t"));
    field.erase(field.find_last_not_of(" \t") + 1);
    fields.push_back(field);
  }
  if (!line.empty() && line.back() == ',') fields.push_back("");
  return fields;
}

std::string Number(double value, int precision) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(precision) << value;
  return s.str();
}

}  // namespace

DetectionFormat ParseDetectionFormat(const std::string& name) {
  if (name == "auto") return DetectionFormat::kAuto;
  if (name == "kitti-object") return DetectionFormat::kKittiObject;
  if (name == "kitti-tracking") return DetectionFormat::kKittiTracking;
  if (name == "ab3dmot") return DetectionFormat::kAb3dmot;
  SAMP_THROW() << "detection format '" << name << "' is not one of auto, kitti-object, kitti-tracking, ab3dmot";
}

std::string DetectionFormatName(DetectionFormat format) {
  switch (format) {
    case DetectionFormat::kAuto: return "auto";
    case DetectionFormat::kKittiObject: return "kitti-object";
    case DetectionFormat::kKittiTracking: return "kitti-tracking";
    case DetectionFormat::kAb3dmot: return "ab3dmot";
  }
  return "auto";
}

DetectionFormat SniffDetectionFormat(const std::string& path) {
  DetectionFormat format = DetectionFormat::kAuto;
  bool decided = false;
  ForEachLine(path, "detection", [&](int n, const std::string& line) {
    if (decided || IsBlank(line)) return;
    decided = true;
    if (line.find(',') != std::string::npos) {
      format = DetectionFormat::kAb3dmot;
      return;
    }
    const size_t columns = Tokenize(line).size();
    if (columns == 17 || columns == 18) {
      format = DetectionFormat::kKittiTracking;
    } else if (columns == 15 || columns == 16) {
      format = DetectionFormat::kKittiObject;
    } else {
      SAMP_THROW() << At(path, n) << columns
                   << " columns: not a detection file (kitti-object: 15 or 16 columns, kitti-tracking: 17 or 18, "
                      "ab3dmot: 15 comma-separated fields)";
    }
  });
  return format;
}

std::vector<ObjectLabel> ReadDetectionFile(const std::string& path, DetectionFormat format) {
  if (format == DetectionFormat::kAuto) format = SniffDetectionFormat(path);
  switch (format) {
    case DetectionFormat::kAuto: return {};  // empty file
    case DetectionFormat::kAb3dmot: return ReadAb3dmotDetections(path);
    case DetectionFormat::kKittiTracking: {
      std::vector<ObjectLabel> labels = ReadTrackingLabels(path);
      for (ObjectLabel& label : labels) label.track_id = -1;  // detections: identities are the tracker's job
      return labels;
    }
    case DetectionFormat::kKittiObject: break;
  }
  SAMP_THROW() << path << ": KITTI object lines have no frame column (one file per frame): give a folder of "
               << "<seq>_<ff>.txt files, or a kitti-tracking or ab3dmot file for the sequence";
}

std::vector<ObjectLabel> ReadAb3dmotDetections(const std::string& path) {
  std::vector<ObjectLabel> labels;
  ForEachLine(path, "AB3DMOT detection", [&](int n, const std::string& line) {
    if (IsBlank(line)) return;
    const std::vector<std::string> f = SplitCommas(line);
    SAMP_CHECK(f.size() == 15) << At(path, n) << f.size()
                               << " fields, expected 15 (frame,type,x1,y1,x2,y2,score,h,w,l,x,y,z,ry,alpha)";
    const int frame = ParseInt(f[0], path, n, "frame");
    SAMP_CHECK(frame >= 0) << At(path, n) << "frame " << frame << " is negative";
    const int type_id = ParseInt(f[1], path, n, "type");
    const char* type = Ab3dmotTypeName(type_id);
    SAMP_CHECK(type != nullptr) << At(path, n) << "unknown class id " << type_id
                                << " (AB3DMOT: 1 = Pedestrian, 2 = Car, 3 = Cyclist)";
    // The KITTI object columns, truncation and occlusion unknown (0).
    const std::vector<std::string> columns = {type, "0",   "0",   f[14], f[2],  f[3],  f[4], f[5],
                                              f[7], f[8],  f[9],  f[10], f[11], f[12], f[13], f[6]};
    ObjectLabel label = ParseObject(columns, 0, path, n);
    label.frame = frame;
    label.track_id = -1;
    labels.push_back(label);
  });
  return labels;
}

void WriteAb3dmotDetections(const std::string& path, const std::vector<ObjectLabel>& labels) {
  std::string text;
  for (const ObjectLabel& l : labels) {
    const int id = Ab3dmotTypeId(l.type);
    SAMP_CHECK(id > 0) << "WriteAb3dmotDetections " << path << ": type " << l.type
                       << " has no AB3DMOT class id (Pedestrian, Car, Cyclist)";
    SAMP_CHECK(l.frame >= 0) << "WriteAb3dmotDetections " << path << ": a label without frame";
    const double values[] = {l.box_2d[0], l.box_2d[1], l.box_2d[2], l.box_2d[3], l.score,   l.height,
                             l.width,     l.length,    l.position.x(), l.position.y(), l.position.z(),
                             l.rotation_y, l.alpha};
    std::string line = std::to_string(l.frame) + "," + std::to_string(id);
    for (size_t k = 0; k < sizeof(values) / sizeof(values[0]); ++k) {
      SAMP_CHECK(std::isfinite(values[k])) << "WriteAb3dmotDetections " << path << ": a non-finite value";
      line += "," + Number(values[k], k < 4 ? 4 : 6);
    }
    text += line + "\n";
  }
  WriteTextFileAtomically(path, text);
}

}  // namespace samp
