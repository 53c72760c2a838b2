#include "libsamp/data/sequence_layout.h"

#include <cstdio>
#include <filesystem>
#include <utility>

#include "libsamp/core/error.h"

namespace samp {
namespace fs = std::filesystem;

SequenceLayout::SequenceLayout(std::string directory, std::string name)
    : directory_(std::move(directory)), name_(std::move(name)) {}

std::string SequenceLayout::FrameTag(const std::string& name, int frame) {
  char digits[32];
  std::snprintf(digits, sizeof(digits), "%02d", frame);
  return name + "_" + digits;
}

std::string SequenceLayout::FrameFileName(const std::string& name, int frame,
                                          const std::string& extension) {
  return FrameTag(name, frame) + extension;
}

int SequenceLayout::FrameOfFileName(const std::string& path, const std::string& name,
                                    const std::string& extension) {
  const std::string file_name = fs::path(path).filename().string();
  const std::string prefix = name + "_";
  if (file_name.size() <= prefix.size() + extension.size()) return -1;
  if (file_name.compare(0, prefix.size(), prefix) != 0) return -1;
  if (file_name.compare(file_name.size() - extension.size(), extension.size(), extension) != 0) return -1;
  const std::string digits =
      file_name.substr(prefix.size(), file_name.size() - prefix.size() - extension.size());
  for (const char c : digits)
    if (c < '0' || c > '9') return -1;
  SAMP_CHECK(digits.size() <= 6) << path << ": frame number '" << digits << "' too long";
  return std::stoi(digits);
}

std::string SequenceLayout::Folder(const char* folder) const {
  return (fs::path(directory_) / folder).string();
}

std::string SequenceLayout::FrameFile(const char* folder, int frame, const char* extension) const {
  return (fs::path(directory_) / folder / FrameFileName(name_, frame, extension)).string();
}

std::string SequenceLayout::Calibration() const {
  return (fs::path(directory_) / kCalibrationFolder / (name_ + ".txt")).string();
}
std::string SequenceLayout::Poses() const {
  return (fs::path(directory_) / kPosesFolder / (name_ + ".txt")).string();
}
std::string SequenceLayout::LeftImage(int frame) const { return FrameFile(kLeftImageFolder, frame, ".png"); }
std::string SequenceLayout::RightImage(int frame) const { return FrameFile(kRightImageFolder, frame, ".png"); }
std::string SequenceLayout::Disparity(int frame) const { return FrameFile(kDisparityFolder, frame, ".png"); }
std::string SequenceLayout::Detections(int frame) const { return FrameFile(kDetectionsFolder, frame, ".txt"); }
std::string SequenceLayout::Plane(int frame) const { return FrameFile(kPlanesFolder, frame, ".txt"); }

std::string SequenceLayout::GroundTruthFolder() const { return Folder(kGroundTruthFolder); }
std::string SequenceLayout::GroundTruthLabels() const {
  return (fs::path(directory_) / kGroundTruthFolder / "label_02" / (name_ + ".txt")).string();
}
std::string SequenceLayout::GroundTruthDepth(int frame) const {
  return (fs::path(directory_) / kGroundTruthFolder / "depth" / FrameFileName(name_, frame, ".png")).string();
}
std::string SequenceLayout::GroundTruthObjectMap(int frame) const {
  return (fs::path(directory_) / kGroundTruthFolder / "obj_map" / FrameFileName(name_, frame, ".png")).string();
}
std::string SequenceLayout::GroundTruthMesh(int track_id) const {
  return (fs::path(directory_) / kGroundTruthFolder / "meshes" / ("track_" + std::to_string(track_id) + ".ply"))
      .string();
}
std::string SequenceLayout::GroundTruthCars() const {
  return (fs::path(directory_) / kGroundTruthFolder / "cars.json").string();
}

}  // namespace samp
