#include "libsamp/viz/sequence_files.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "libsamp/core/error.h"

namespace samp::sequence_files {
namespace {

namespace fs = std::filesystem;

// The numbers of every non-blank line, with its 1-based line number.
std::vector<std::pair<int, std::vector<std::string>>> Lines(const std::string& path) {
  std::ifstream in(path);
  SAMP_CHECK(in) << "cannot open " << path;
  std::vector<std::pair<int, std::vector<std::string>>> lines;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    std::istringstream words(line);
    std::vector<std::string> tokens;
    for (std::string w; words >> w;) tokens.push_back(w);
    if (!tokens.empty()) lines.emplace_back(number, std::move(tokens));
  }
  return lines;
}

double Number(const std::string& token, const std::string& path, int line) {
  char* end = nullptr;
  const double v = std::strtod(token.c_str(), &end);
  SAMP_CHECK(end != token.c_str() && *end == '\0' && std::isfinite(v))
      << path << ":" << line << ": '" << token << "' is not a finite number";
  return v;
}

ObjectLabel Label(const std::vector<std::string>& t, size_t first, const std::string& path, int line) {
  ObjectLabel l;
  l.type = t[first];
  for (int i = 0; i < 4; ++i) l.box_2d[i] = Number(t[first + 4 + i], path, line);
  l.height = Number(t[first + 8], path, line);
  l.width = Number(t[first + 9], path, line);
  l.length = Number(t[first + 10], path, line);
  for (int i = 0; i < 3; ++i) l.position[i] = Number(t[first + 11 + i], path, line);
  l.rotation_y = Number(t[first + 14], path, line);
  return l;
}

// The frame number of "<name>_<digits><extension>", -1 otherwise.
int FrameOf(const fs::path& file, const std::string& name, const std::string& extension) {
  const std::string f = file.filename().string();
  if (f.size() <= name.size() + 1 + extension.size() || f.compare(0, name.size() + 1, name + "_") != 0 ||
      f.compare(f.size() - extension.size(), extension.size(), extension) != 0)
    return -1;
  const std::string digits = f.substr(name.size() + 1, f.size() - name.size() - 1 - extension.size());
  if (digits.empty() || digits.size() > 6 || !std::all_of(digits.begin(), digits.end(), ::isdigit)) return -1;
  return std::stoi(digits);
}

}  // namespace

std::string FrameFileName(const std::string& name, int frame, const std::string& extension) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "_%02d", frame);
  return name + buffer + extension;
}

SequenceFiles ListSequence(const std::string& directory) {
  const fs::path root(directory);
  SAMP_CHECK(fs::is_directory(root / "calib")) << "sequence " << directory << " has no calib/ folder";
  std::vector<fs::path> calibs;
  for (const auto& e : fs::directory_iterator(root / "calib"))
    if (e.is_regular_file() && e.path().extension() == ".txt") calibs.push_back(e.path());
  std::sort(calibs.begin(), calibs.end());
  SAMP_CHECK(!calibs.empty()) << (root / "calib").string() << ": no <seq>.txt calibration file";
  fs::path calib = calibs.front();
  for (const fs::path& c : calibs)
    if (c.stem() == root.filename()) calib = c;
  SAMP_CHECK(calibs.size() == 1 || calib.stem() == root.filename())
      << (root / "calib").string() << ": several calibration files and none named like the folder";
  SequenceFiles files;
  files.name = calib.stem().string();
  files.calibration = calib.string();
  const fs::path poses = root / "poses" / (files.name + ".txt");
  if (fs::exists(poses)) files.poses = poses.string();
  std::map<int, FrameFiles> frames;
  auto scan = [&](const char* folder, const char* extension, std::string FrameFiles::*field) {
    if (!fs::is_directory(root / folder)) return;
    for (const auto& e : fs::directory_iterator(root / folder)) {
      const int frame = FrameOf(e.path(), files.name, extension);
      if (frame < 0) continue;
      frames[frame].frame = frame;
      frames[frame].*field = e.path().string();
    }
  };
  scan("image_2", ".png", &FrameFiles::image_left);
  scan("detections", ".txt", &FrameFiles::detections);
  scan("planes", ".txt", &FrameFiles::plane);
  for (auto& [frame, f] : frames)
    if (!f.image_left.empty() || !f.detections.empty()) files.frames.push_back(f);
  SAMP_CHECK(!files.frames.empty()) << "sequence " << directory << " has no frames in image_2/ or detections/";
  return files;
}

PinholeCamera ReadCalibration(const std::string& path, int width, int height) {
  for (const auto& [line, t] : Lines(path)) {
    if (t[0] != "P2:") continue;
    SAMP_CHECK(t.size() == 13) << path << ":" << line << ": P2 needs 12 numbers";
    PinholeCamera camera;
    camera.fx = Number(t[1], path, line);
    camera.cx = Number(t[3], path, line);
    camera.fy = Number(t[6], path, line);
    camera.cy = Number(t[7], path, line);
    camera.width = width, camera.height = height;
    SAMP_CHECK(camera.fx > 0 && camera.fy > 0) << path << ":" << line << ": P2 has no positive focal length";
    return camera;
  }
  SAMP_THROW() << path << ": no P2 line";
}

std::vector<Eigen::Isometry3d> ReadPoses(const std::string& path) {
  std::vector<Eigen::Isometry3d> poses;
  for (const auto& [line, t] : Lines(path)) {
    SAMP_CHECK(t.size() == 12) << path << ":" << line << ": a pose needs 12 numbers, got " << t.size();
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) pose.matrix()(r, c) = Number(t[size_t(4 * r + c)], path, line);
    poses.push_back(pose);
  }
  return poses;
}

std::vector<ObjectLabel> ReadLabels(const std::string& path) {
  std::vector<ObjectLabel> labels;
  for (const auto& [line, t] : Lines(path)) {
    SAMP_CHECK(t.size() == 15 || t.size() == 16) << path << ":" << line << ": expected 15 or 16 columns, got " << t.size();
    labels.push_back(Label(t, 0, path, line));
  }
  return labels;
}

std::vector<ObjectLabel> ReadTrackingLabels(const std::string& path) {
  std::vector<ObjectLabel> labels;
  for (const auto& [line, t] : Lines(path)) {
    SAMP_CHECK(t.size() == 17 || t.size() == 18) << path << ":" << line << ": expected 17 or 18 columns, got " << t.size();
    ObjectLabel l = Label(t, 2, path, line);
    l.frame = int(Number(t[0], path, line));
    l.track_id = int(Number(t[1], path, line));
    labels.push_back(l);
  }
  return labels;
}

Eigen::Vector4d ReadPlane(const std::string& path) {
  const auto lines = Lines(path);
  SAMP_CHECK(!lines.empty() && lines.back().second.size() == 4) << path << ": the last line must hold a b c d";
  Eigen::Vector4d p;
  for (int i = 0; i < 4; ++i) p[i] = Number(lines.back().second[size_t(i)], path, lines.back().first);
  const double n = p.head<3>().norm();
  SAMP_CHECK(n > 0) << path << ": the plane normal is zero";
  p /= n;
  if (p[1] > 0) p = -p;  // normal up (towards -y of the camera)
  return p;
}

bool SameObjectType(const std::string& a, const std::string& b) {
  return a.size() == b.size() &&
         std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) { return std::tolower(x) == std::tolower(y); });
}

}  // namespace samp::sequence_files
