#include "libsamp/data/kitti_io.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <functional>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <sstream>

#include <Eigen/SVD>
#include <opencv2/imgcodecs.hpp>

#include "libsamp/core/atomic_file.h"
#include "libsamp/core/error.h"
#include "libsamp/core/log.h"
#include "libsamp/data/kitti_text.h"

namespace samp {
// The text helpers are shared with the other KITTI readers (data/kitti_text.h).
namespace kitti_text {

// A text file read into lines, for parsers that report "path:line: problem".
struct TextFile {
  std::string path;
  std::vector<std::string> lines;
};

// Text files are streamed line by line (a 100 MB poses file once took
// 913 MB as a vector of lines); a line longer than kMaxLineBytes is an error
// naming the file and line, so memory stays bounded by what is parsed.
constexpr size_t kMaxLineBytes = size_t(1) << 20;
// Calibration and plane files are read whole; they hold a few lines.
constexpr size_t kMaxSmallTextBytes = size_t(1) << 20;

void ForEachLine(const std::string& path, const char* what,
                 const std::function<void(int line_number, const std::string& line)>& f) {
  std::ifstream stream(path, std::ios::binary);
  SAMP_CHECK(stream.good()) << "cannot open " << what << " file " << path;
  std::streambuf* buffer = stream.rdbuf();
  std::string line;
  int line_number = 0;
  for (;;) {
    line.clear();
    bool any = false;
    for (int c; (c = buffer->sbumpc()) != std::char_traits<char>::eof();) {
      any = true;
      if (c == '\n') break;
      line.push_back(char(c));
      SAMP_CHECK(line.size() <= kMaxLineBytes)
          << path << ":" << line_number + 1 << ": line longer than " << kMaxLineBytes << " bytes: not a " << what
          << " file";
    }
    if (!any) break;
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    f(line_number, line);
  }
  SAMP_CHECK(!stream.bad()) << "error reading " << what << " file " << path;
}

TextFile ReadTextFile(const std::string& path, const char* what) {
  TextFile file{path, {}};
  size_t bytes = 0;
  ForEachLine(path, what, [&](int, const std::string& line) {
    bytes += line.size() + 1;
    SAMP_CHECK(bytes <= kMaxSmallTextBytes)
        << path << ": more than " << kMaxSmallTextBytes << " bytes: not a " << what << " file";
    file.lines.push_back(line);
  });
  return file;
}

std::vector<std::string> Tokenize(const std::string& line) {
  std::istringstream stream(line);
  std::vector<std::string> tokens;
  std::string token;
  while (stream >> token) tokens.push_back(token);
  return tokens;
}

bool IsBlank(const std::string& line) {
  return std::all_of(line.begin(), line.end(), [](unsigned char c) { return std::isspace(c); });
}

std::vector<std::string> ParseSequenceList(const std::string& sequences, size_t digits) {
  std::vector<std::string> names;
  std::stringstream list(sequences);
  for (std::string name; std::getline(list, name, ',');) {
    name.erase(0, name.find_first_not_of(" \t"));
    name.erase(name.find_last_not_of(" \t") + 1);
    SAMP_CHECK(!name.empty()) << "--sequence '" << sequences << "': empty sequence name";
    if (name.size() < digits && name.find_first_not_of("0123456789") == std::string::npos)
      name = std::string(digits - name.size(), '0') + name;
    SAMP_CHECK(std::find(names.begin(), names.end(), name) == names.end()) << "--sequence lists " << name << " twice";
    names.push_back(name);
  }
  SAMP_CHECK(!names.empty()) << "--sequence is empty: give names (e.g. " << std::string(digits - 1, '0') << "4,"
                             << std::string(digits - 2, '0') << "11) or all";
  return names;
}

// Plausibility bounds of a label line (docs/reliability.md): loose on purpose,
// they refuse garbage, not unusual cars.
constexpr double kMaxLabelPixel = 1e5;        // |2D box coordinate|, px
constexpr double kMaxObjectSize = 50.0;       // h, w, l, m
constexpr double kMaxObjectDistance = 1e4;    // |x|, |y|, |z| of the location, m
constexpr double kMaxRotationY = 4 * 3.14159265358979323846;  // |rotation_y|, |alpha|, rad

// Location prefix of messages: "path:line: ".
std::string At(const std::string& path, int line_number) {
  return path + ":" + std::to_string(line_number) + ": ";
}

double ParseDouble(const std::string& token, const std::string& path, int line_number,
                   const char* field) {
  errno = 0;
  char* end = nullptr;
  const double value = std::strtod(token.c_str(), &end);
  SAMP_CHECK(end != token.c_str() && *end == '\0')
      << At(path, line_number) << field << " '" << token << "' is not a number";
  // ERANGE on underflow (a subnormal such as -4e-320, or a value that
  // rounds to 0) is a finite number; only an overflow to HUGE_VAL is not.
  SAMP_CHECK(std::isfinite(value) && !(errno == ERANGE && std::abs(value) == HUGE_VAL))
      << At(path, line_number) << field << " '" << token << "' is not a finite number";
  return value;
}

int ParseInt(const std::string& token, const std::string& path, int line_number, const char* field) {
  errno = 0;
  char* end = nullptr;
  const long value = std::strtol(token.c_str(), &end, 10);
  SAMP_CHECK(end != token.c_str() && *end == '\0' && errno != ERANGE &&
             value >= -2147483647L && value <= 2147483647L)
      << At(path, line_number) << field << " '" << token << "' is not an integer";
  return static_cast<int>(value);
}

// Occlusion is an integer in KITTI, but some writers print "-1.00" or "0.0".
int ParseIntegral(const std::string& token, const std::string& path, int line_number,
                  const char* field) {
  const double value = ParseDouble(token, path, line_number, field);
  SAMP_CHECK(value == std::floor(value) && std::abs(value) < 1e9)
      << At(path, line_number) << field << " '" << token << "' is not an integer";
  return static_cast<int>(value);
}

// Parses the 15/16 object columns starting at tokens[first].
ObjectLabel ParseObject(const std::vector<std::string>& tokens, size_t first,
                        const std::string& path, int line_number) {
  ObjectLabel label;
  const std::string& p = path;
  const int n = line_number;
  label.type = tokens[first];
  SAMP_CHECK(!label.type.empty() && !std::isdigit(static_cast<unsigned char>(label.type[0])) &&
             label.type[0] != '-' && label.type[0] != '.')
      << At(p, n) << "object type '" << label.type << "' is not a name";
  label.truncation = ParseDouble(tokens[first + 1], p, n, "truncation");
  label.occlusion = ParseIntegral(tokens[first + 2], p, n, "occlusion");
  label.alpha = ParseDouble(tokens[first + 3], p, n, "alpha");
  for (int i = 0; i < 4; ++i) label.box_2d[i] = ParseDouble(tokens[first + 4 + i], p, n, "2D box");
  label.height = ParseDouble(tokens[first + 8], p, n, "height");
  label.width = ParseDouble(tokens[first + 9], p, n, "width");
  label.length = ParseDouble(tokens[first + 10], p, n, "length");
  for (int i = 0; i < 3; ++i) label.position[i] = ParseDouble(tokens[first + 11 + i], p, n, "location");
  label.rotation_y = ParseDouble(tokens[first + 14], p, n, "rotation_y");
  if (tokens.size() > first + 15) label.score = ParseDouble(tokens[first + 15], p, n, "score");

  if (SameObjectType(label.type, "DontCare")) return label;  // -1/-1000 placeholders
  SAMP_CHECK(label.box_2d[2] >= label.box_2d[0] && label.box_2d[3] >= label.box_2d[1])
      << At(p, n) << "2D box (" << label.box_2d.transpose() << ") has x2 < x1 or y2 < y1";
  SAMP_CHECK(label.height >= 0 && label.width >= 0 && label.length >= 0)
      << At(p, n) << "negative object size h w l = " << label.height << " " << label.width << " "
      << label.length;
  SAMP_CHECK(label.position.z() > 0)
      << At(p, n) << "object at z = " << label.position.z() << " m is behind the camera";
  // Plausibility (docs/reliability.md, "Plausibility checks"): values that
  // parse but describe no car in a camera image.
  for (int i = 0; i < 4; ++i) {
    SAMP_CHECK(std::abs(label.box_2d[i]) <= kMaxLabelPixel)
        << At(p, n) << "2D box coordinate " << label.box_2d[i] << " px is beyond +-" << kMaxLabelPixel
        << " px: not a box in an image";
  }
  SAMP_CHECK(label.height <= kMaxObjectSize && label.width <= kMaxObjectSize && label.length <= kMaxObjectSize)
      << At(p, n) << "object size h w l = " << label.height << " " << label.width << " " << label.length
      << " m: more than " << kMaxObjectSize << " m";
  SAMP_CHECK(label.position.cwiseAbs().maxCoeff() <= kMaxObjectDistance)
      << At(p, n) << "object location (" << label.position.transpose() << ") is more than "
      << kMaxObjectDistance << " m from the camera";
  SAMP_CHECK(std::abs(label.rotation_y) <= kMaxRotationY && std::abs(label.alpha) <= kMaxRotationY)
      << At(p, n) << "rotation_y " << label.rotation_y << " / alpha " << label.alpha
      << " is beyond +-" << kMaxRotationY << " rad (KITTI's are within +-pi)";
  return label;
}

std::string FormatNumber(double value, int precision) {
  std::ostringstream stream;
  stream << std::fixed << std::setprecision(precision) << value;
  std::string s = stream.str();
  if (s.find('.') != std::string::npos) {  // "1.5000" -> "1.5", "-0.0000" -> "0"
    while (!s.empty() && s.back() == '0') s.pop_back();
    if (!s.empty() && s.back() == '.') s.pop_back();
  }
  if (s == "-0") s = "0";
  return s;
}

void CheckLabelForWriting(const ObjectLabel& label) {
  SAMP_CHECK(!label.type.empty() &&
             std::none_of(label.type.begin(), label.type.end(),
                          [](unsigned char c) { return std::isspace(c); }))
      << "label type '" << label.type << "' is empty or contains whitespace";
  const bool finite = std::isfinite(label.truncation) && std::isfinite(label.alpha) &&
                      label.box_2d.allFinite() && std::isfinite(label.height) &&
                      std::isfinite(label.width) && std::isfinite(label.length) &&
                      label.position.allFinite() && std::isfinite(label.rotation_y) &&
                      std::isfinite(label.score);
  SAMP_CHECK(finite) << "label of type " << label.type << " (frame " << label.frame << ", track "
                     << label.track_id << ") has a non-finite value";
}

std::string FormatObjectColumns(const ObjectLabel& label) {
  CheckLabelForWriting(label);
  std::ostringstream s;
  s << label.type << ' ' << FormatNumber(label.truncation, 2) << ' ' << label.occlusion << ' '
    << FormatNumber(label.alpha, 4);
  for (int i = 0; i < 4; ++i) s << ' ' << FormatNumber(label.box_2d[i], 2);
  s << ' ' << FormatNumber(label.height, 4) << ' ' << FormatNumber(label.width, 4) << ' '
    << FormatNumber(label.length, 4);
  for (int i = 0; i < 3; ++i) s << ' ' << FormatNumber(label.position[i], 4);
  s << ' ' << FormatNumber(label.rotation_y, 4) << ' ' << FormatNumber(label.score, 4);
  return s.str();
}

std::string FormatMatrixRow(const Eigen::Matrix<double, 3, 4>& m) {
  std::ostringstream s;
  s << std::setprecision(12);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) s << (r + c > 0 ? " " : "") << m(r, c);
  return s.str();
}

}  // namespace kitti_text

using namespace kitti_text;

bool SameObjectType(const std::string& a, const std::string& b) {
  return a.size() == b.size() &&
         std::equal(a.begin(), a.end(), b.begin(), [](unsigned char x, unsigned char y) {
           return std::tolower(x) == std::tolower(y);
         });
}

StereoCalibration ReadCalibration(const std::string& path, int image_width, int image_height) {
  const bool size_known = image_width != 0 || image_height != 0;
  SAMP_CHECK(!size_known || (image_width > 0 && image_height > 0))
      << "ReadCalibration: image size " << image_width << "x" << image_height
      << " must be positive (0x0 = not known)";
  if (!size_known) image_width = 1242, image_height = 375;
  const TextFile file = ReadTextFile(path, "calibration");
  Eigen::Matrix<double, 3, 4> p[2];
  int line_of[2] = {0, 0};
  for (size_t i = 0; i < file.lines.size(); ++i) {
    const int n = static_cast<int>(i) + 1;
    const std::vector<std::string> tokens = Tokenize(file.lines[i]);
    if (tokens.empty()) continue;
    int which = -1;
    // KITTI stereo 2015's calib_cam_to_cam names them P_rect_02 / P_rect_03.
    if (tokens[0] == "P2:" || tokens[0] == "P_rect_02:") which = 0;
    if (tokens[0] == "P3:" || tokens[0] == "P_rect_03:") which = 1;
    if (which < 0) continue;
    SAMP_CHECK(line_of[which] == 0) << At(path, n) << tokens[0] << " given twice (first on line "
                                    << line_of[which] << ")";
    SAMP_CHECK(tokens.size() == 13) << At(path, n) << tokens[0] << " has " << tokens.size() - 1
                                    << " numbers, expected 12";
    for (int k = 0; k < 12; ++k) {
      const double value = ParseDouble(tokens[k + 1], path, n, tokens[0].c_str());
      SAMP_CHECK(std::abs(value) <= kMaxCalibrationValue)
          << At(path, n) << tokens[0] << " entry (" << k / 4 << "," << k % 4 << ") = " << value
          << " is not a plausible calibration value (|v| > " << kMaxCalibrationValue << ")";
      p[which](k / 4, k % 4) = value;
    }
    line_of[which] = n;
  }
  SAMP_CHECK(line_of[0] > 0) << path << ": no 'P2:' line (left camera; 'P_rect_02:' in calib_cam_to_cam)";
  SAMP_CHECK(line_of[1] > 0) << path
                             << ": no 'P3:' line (right camera; 'P_rect_03:' in calib_cam_to_cam), needed for the "
                                "baseline";
  StereoCalibration calibration;
  PinholeCamera& camera = calibration.camera;
  camera.fx = p[0](0, 0);
  camera.fy = p[0](1, 1);
  camera.cx = p[0](0, 2);
  camera.cy = p[0](1, 2);
  camera.width = image_width;
  camera.height = image_height;
  SAMP_CHECK(camera.fx > 0 && camera.fy > 0)
      << At(path, line_of[0]) << "P2 focal lengths " << camera.fx << ", " << camera.fy
      << " must be positive";
  SAMP_CHECK(camera.fx > kMinFocalLengthPx && camera.fx <= kMaxFocalLengthPx &&
             camera.fy > kMinFocalLengthPx && camera.fy <= kMaxFocalLengthPx)
      << At(path, line_of[0]) << "P2 focal lengths fx = " << camera.fx << ", fy = " << camera.fy
      << " px are not plausible (must be in (" << kMinFocalLengthPx << ", " << kMaxFocalLengthPx
      << "] px)";
  if (size_known) {
    SAMP_CHECK(camera.cx >= 0 && camera.cx <= image_width && camera.cy >= 0 && camera.cy <= image_height)
        << At(path, line_of[0]) << "P2 principal point (" << camera.cx << ", " << camera.cy
        << ") px lies outside the " << image_width << "x" << image_height << " image";
  }
  SAMP_CHECK(std::abs(p[1](0, 0) - camera.fx) <= 1e-3 * camera.fx &&
             std::abs(p[1](0, 2) - camera.cx) <= 1.0 && std::abs(p[1](1, 2) - camera.cy) <= 1.0)
      << At(path, line_of[1]) << "P3 intrinsics differ from P2's: the pair is not rectified";
  calibration.baseline = (p[0](0, 3) - p[1](0, 3)) / camera.fx;
  SAMP_CHECK(calibration.baseline > 0)
      << path << ": baseline (P2[0,3] - P3[0,3]) / fx = " << calibration.baseline
      << " m is not positive (P3 must be the right camera)";
  SAMP_CHECK(calibration.baseline <= kMaxBaseline)
      << path << ": baseline (P2[0,3] - P3[0,3]) / fx = " << calibration.baseline
      << " m is not plausible for a stereo rig (> " << kMaxBaseline << " m)";
  return calibration;
}

Eigen::Vector3d ReadCamera2Offset(const std::string& path) {
  const StereoCalibration calibration = ReadCalibration(path);  // checks the file
  const TextFile file = ReadTextFile(path, "calibration");
  for (const std::string& line : file.lines) {
    const std::vector<std::string> tokens = Tokenize(line);
    if (tokens.size() != 13 || (tokens[0] != "P2:" && tokens[0] != "P_rect_02:")) continue;
    const PinholeCamera& c = calibration.camera;
    const Eigen::Vector3d column(std::strtod(tokens[4].c_str(), nullptr), std::strtod(tokens[8].c_str(), nullptr),
                                 std::strtod(tokens[12].c_str(), nullptr));
    Eigen::Matrix3d k;
    k << c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1;
    return k.inverse() * column;
  }
  return Eigen::Vector3d::Zero();
}

void WriteCalibration(const std::string& path, const StereoCalibration& calibration) {
  const PinholeCamera& c = calibration.camera;
  SAMP_CHECK(c.fx > 0 && c.fy > 0 && calibration.baseline > 0)
      << "WriteCalibration " << path << ": focal lengths and baseline must be positive";
  Eigen::Matrix<double, 3, 4> p2 = Eigen::Matrix<double, 3, 4>::Zero();
  p2(0, 0) = c.fx;
  p2(1, 1) = c.fy;
  p2(0, 2) = c.cx;
  p2(1, 2) = c.cy;
  p2(2, 2) = 1.0;
  Eigen::Matrix<double, 3, 4> p3 = p2;
  p3(0, 3) = -c.fx * calibration.baseline;
  WriteTextFileAtomically(path, "P2: " + FormatMatrixRow(p2) + "\nP3: " + FormatMatrixRow(p3) + "\n");
}

std::vector<ObjectLabel> ReadLabels(const std::string& path) {
  std::vector<ObjectLabel> labels;
  ForEachLine(path, "label", [&](int n, const std::string& line) {
    if (IsBlank(line)) return;
    const std::vector<std::string> tokens = Tokenize(line);
    SAMP_CHECK(tokens.size() == 15 || tokens.size() == 16)
        << At(path, n) << tokens.size()
        << " columns, expected 15 or 16 (type trunc occ alpha x1 y1 x2 y2 h w l x y z ry [score])";
    labels.push_back(ParseObject(tokens, 0, path, n));
  });
  return labels;
}

std::vector<ObjectLabel> ReadTrackingLabels(const std::string& path) {
  std::vector<ObjectLabel> labels;
  ForEachLine(path, "tracking label", [&](int n, const std::string& line) {
    if (IsBlank(line)) return;
    const std::vector<std::string> tokens = Tokenize(line);
    SAMP_CHECK(tokens.size() == 17 || tokens.size() == 18)
        << At(path, n) << tokens.size()
        << " columns, expected 17 or 18 (frame track_id type trunc occ alpha x1 y1 x2 y2 h w l x y "
           "z ry [score])";
    const int frame = ParseInt(tokens[0], path, n, "frame");
    const int track_id = ParseInt(tokens[1], path, n, "track_id");
    SAMP_CHECK(frame >= 0) << At(path, n) << "frame " << frame << " is negative";
    SAMP_CHECK(track_id >= -1) << At(path, n) << "track_id " << track_id << " is below -1";
    ObjectLabel label = ParseObject(tokens, 2, path, n);
    label.frame = frame;
    label.track_id = track_id;
    labels.push_back(label);
  });
  return labels;
}

std::string FormatLabel(const ObjectLabel& label) { return FormatObjectColumns(label); }

std::string FormatTrackingLabel(const ObjectLabel& label) {
  SAMP_CHECK(label.frame >= 0) << "tracking label of type " << label.type << " has frame "
                               << label.frame;
  return std::to_string(label.frame) + " " + std::to_string(label.track_id) + " " +
         FormatObjectColumns(label);
}

void WriteLabels(const std::string& path, const std::vector<ObjectLabel>& labels) {
  std::string text;
  for (const ObjectLabel& label : labels) text += FormatLabel(label) + "\n";
  WriteTextFileAtomically(path, text);
}

void WriteTrackingLabels(const std::string& path, const std::vector<ObjectLabel>& labels) {
  std::string text;
  for (const ObjectLabel& label : labels) text += FormatTrackingLabel(label) + "\n";
  WriteTextFileAtomically(path, text);
}

Eigen::Vector4d ReadPlane(const std::string& path) {
  const TextFile file = ReadTextFile(path, "plane");
  std::vector<int> content;  // indices of non-blank lines
  for (size_t i = 0; i < file.lines.size(); ++i)
    if (!IsBlank(file.lines[i])) content.push_back(static_cast<int>(i));
  SAMP_CHECK(content.size() == 4)
      << path << ": " << content.size()
      << " non-blank lines, expected 4 (\"# Matrix\", \"WIDTH 4\", \"HEIGHT 1\", \"a b c d\")";
  const std::vector<std::string> header = Tokenize(file.lines[content[0]]);
  SAMP_CHECK(header.size() == 2 && header[0] == "#" && header[1] == "Matrix")
      << At(path, content[0] + 1) << "expected \"# Matrix\"";
  const std::vector<std::string> width = Tokenize(file.lines[content[1]]);
  SAMP_CHECK(width.size() == 2 && width[0] == "WIDTH" && width[1] == "4")
      << At(path, content[1] + 1) << "expected \"WIDTH 4\"";
  const std::vector<std::string> height = Tokenize(file.lines[content[2]]);
  SAMP_CHECK(height.size() == 2 && height[0] == "HEIGHT" && height[1] == "1")
      << At(path, content[2] + 1) << "expected \"HEIGHT 1\"";
  const int n = content[3] + 1;
  const std::vector<std::string> values = Tokenize(file.lines[content[3]]);
  SAMP_CHECK(values.size() == 4) << At(path, n) << values.size() << " numbers, expected 4 (a b c d)";
  Eigen::Vector4d plane;
  for (int k = 0; k < 4; ++k) plane[k] = ParseDouble(values[k], path, n, "plane coefficient");
  const double norm = plane.head<3>().norm();
  SAMP_CHECK(std::isfinite(norm))
      << At(path, n) << "plane normal (" << values[0] << " " << values[1] << " " << values[2]
      << ") cannot be scaled to unit length (its length overflows)";
  SAMP_CHECK(norm > 1e-9) << At(path, n) << "plane normal has zero length";
  plane /= norm;
  SAMP_CHECK(std::abs(plane[3]) <= kMaxPlaneOffset)
      << At(path, n) << "plane offset d = " << plane[3] << " m (for the unit normal) is not a road "
      << "plane: farther than " << kMaxPlaneOffset << " m from the camera";
  if (plane[1] > 0) {
    LogDebug() << path << ": plane normal points down, flipped";
    plane = -plane;
  }
  const double tilt_deg = std::acos(std::min(1.0, -plane[1])) * 180.0 / 3.14159265358979323846;
  SAMP_CHECK(tilt_deg <= kMaxPlaneTiltDeg)
      << At(path, n) << "plane normal (" << plane.head<3>().transpose() << ") is tilted " << tilt_deg
      << " deg from the camera's vertical, more than " << kMaxPlaneTiltDeg << " deg: not a road plane";
  return plane;
}

void WritePlane(const std::string& path, const Eigen::Vector4d& plane) {
  SAMP_CHECK(plane.allFinite() && plane.head<3>().norm() > 1e-9)
      << "WritePlane " << path << ": invalid plane " << plane.transpose();
  std::ostringstream s;
  s << std::scientific << std::setprecision(6) << "# Matrix\nWIDTH 4\nHEIGHT 1\n"
    << plane[0] << ' ' << plane[1] << ' ' << plane[2] << ' ' << plane[3] << " \n";
  WriteTextFileAtomically(path, s.str());
}

std::vector<Eigen::Isometry3d> ReadPoses(const std::string& path) {
  std::vector<Eigen::Isometry3d> poses;
  int first_blank = 0;  // only trailing blank lines: a blank line would shift frame numbers
  ForEachLine(path, "poses", [&](int n, const std::string& line) {
    if (IsBlank(line)) {
      if (first_blank == 0) first_blank = n;
      return;
    }
    SAMP_CHECK(first_blank == 0) << At(path, first_blank) << "blank line inside the poses (one line per frame)";
    const std::vector<std::string> tokens = Tokenize(line);
    SAMP_CHECK(tokens.size() == 12) << At(path, n) << tokens.size()
                                    << " numbers, expected 12 (3x4 row-major [R|t])";
    Eigen::Matrix<double, 3, 4> m;
    for (int k = 0; k < 12; ++k) m(k / 4, k % 4) = ParseDouble(tokens[k], path, n, "pose entry");
    const Eigen::Matrix3d rotation = m.leftCols<3>();
    const double orthogonality = (rotation.transpose() * rotation - Eigen::Matrix3d::Identity()).norm();
    SAMP_CHECK(orthogonality < 1e-3 && rotation.determinant() > 0)
        << At(path, n) << "the 3x3 part is not a rotation (|R^T R - I| = " << orthogonality
        << ", det = " << rotation.determinant() << ")";
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    // Re-orthonormalise the rounding of 6-digit files.
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(rotation, Eigen::ComputeFullU | Eigen::ComputeFullV);
    pose.linear() = svd.matrixU() * svd.matrixV().transpose();
    pose.translation() = m.col(3);
    SAMP_CHECK(pose.translation().norm() <= kMaxPoseTranslation)
        << At(path, n) << "translation (" << pose.translation().transpose() << ") m, |t| = "
        << pose.translation().norm() << " m, is not an ego pose (|t| > " << kMaxPoseTranslation << " m)";
    poses.push_back(pose);
  });
  SAMP_CHECK(!poses.empty()) << path << ": no poses";
  return poses;
}

void WritePoses(const std::string& path, const std::vector<Eigen::Isometry3d>& world_from_camera) {
  std::string text;
  for (const Eigen::Isometry3d& pose : world_from_camera) {
    SAMP_CHECK(pose.matrix().allFinite()) << "WritePoses " << path << ": non-finite pose";
    text += FormatMatrixRow(pose.matrix().topRows<3>()) + "\n";
  }
  WriteTextFileAtomically(path, text);
}

PngHeader ReadPngHeader(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  SAMP_CHECK(in.good()) << "cannot open " << path;
  unsigned char bytes[33];
  in.read(reinterpret_cast<char*>(bytes), sizeof(bytes));
  const std::streamsize got = in.gcount();
  static const unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  SAMP_CHECK(got >= 8 && std::memcmp(bytes, kSignature, 8) == 0) << path << ": not a PNG file (no PNG signature)";
  SAMP_CHECK(got == 33) << path << ": PNG file cut before the end of its header (" << got << " bytes)";
  auto u32 = [&](int at) {
    return (uint32_t(bytes[at]) << 24) | (uint32_t(bytes[at + 1]) << 16) | (uint32_t(bytes[at + 2]) << 8) |
           uint32_t(bytes[at + 3]);
  };
  SAMP_CHECK(u32(8) == 13 && std::memcmp(bytes + 12, "IHDR", 4) == 0)
      << path << ": PNG file without an IHDR chunk of 13 bytes first";
  PngHeader header;
  header.width = u32(16);
  header.height = u32(20);
  header.bit_depth = bytes[24];
  const int colour_type = bytes[25];
  SAMP_CHECK(header.width >= 1 && header.height >= 1 && header.width <= 0x7fffffff && header.height <= 0x7fffffff)
      << path << ": PNG header announces " << header.width << " x " << header.height << " pixels";
  switch (colour_type) {
    case 0: header.channels = 1; break;
    case 2: header.channels = 3; break;
    case 3: header.channels = 3; break;
    case 4: header.channels = 2; break;
    case 6: header.channels = 4; break;
    default: SAMP_THROW() << path << ": PNG header has colour type " << colour_type << " (not 0, 2, 3, 4 or 6)";
  }
  const int d = header.bit_depth;
  SAMP_CHECK(d == 1 || d == 2 || d == 4 || d == 8 || d == 16)
      << path << ": PNG header has bit depth " << d << " (not 1, 2, 4, 8 or 16)";
  return header;
}

cv::Mat ReadImage(const std::string& path, int flags, const char* what, int64_t max_bytes) {
  const PngHeader header = ReadPngHeader(path);
  SAMP_CHECK(header.DecodedBytes() <= max_bytes)
      << path << ": the " << what << "'s header announces " << header.width << " x " << header.height
      << " pixels of " << header.channels << " channel(s), " << header.DecodedBytes()
      << " bytes decoded, more than the memory budget of " << max_bytes << " bytes (max_image_bytes)";
  cv::Mat image;
  try {
    image = cv::imread(path, flags);
  } catch (const cv::Exception& e) {
    SAMP_THROW() << path << ": cannot decode the " << what << ": " << e.what();
  }
  SAMP_CHECK(!image.empty()) << path << ": not a readable " << what << " (a PNG file OpenCV cannot decode)";
  return image;
}

cv::Mat ReadDisparity(const std::string& path, const cv::Size& expected_size, int64_t max_bytes) {
  const cv::Mat raw = ReadImage(path, cv::IMREAD_UNCHANGED, "disparity map", max_bytes);
  SAMP_CHECK(raw.type() == CV_16UC1)
      << path << ": disparity PNG must be 1-channel 16-bit, got " << raw.channels() << " channel(s) of "
      << (raw.depth() == CV_8U ? "8-bit" : raw.depth() == CV_16U ? "16-bit" : "other") << " data";
  if (!expected_size.empty()) {
    SAMP_CHECK(raw.size() == expected_size)
        << path << ": disparity is " << raw.cols << "x" << raw.rows << ", expected "
        << expected_size.width << "x" << expected_size.height << " (the image size)";
  }
  cv::Mat disparity;
  raw.convertTo(disparity, CV_32F, 1.0 / 256.0);
  return disparity;
}

void WriteDisparity(const std::string& path, const cv::Mat& disparity_px) {
  SAMP_CHECK(disparity_px.type() == CV_32FC1 && !disparity_px.empty())
      << "WriteDisparity " << path << ": expected a non-empty CV_32FC1 image";
  cv::Mat raw(disparity_px.size(), CV_16UC1);
  for (int r = 0; r < disparity_px.rows; ++r) {
    const float* in = disparity_px.ptr<float>(r);
    uint16_t* out = raw.ptr<uint16_t>(r);
    for (int c = 0; c < disparity_px.cols; ++c) {
      const float d = in[c];
      if (!std::isfinite(d) || d <= 0) {
        out[c] = 0;
        continue;
      }
      const double value = std::round(static_cast<double>(d) * 256.0);
      SAMP_CHECK(value < 65536.0) << "WriteDisparity " << path << ": disparity " << d
                                  << " px at (" << c << ", " << r << ") is >= 256 px";
      out[c] = static_cast<uint16_t>(std::max(1.0, value));  // a tiny positive value stays valid
    }
  }
  // Encoded in memory (the codec from ".png", not from the temporary's name),
  // written with every byte checked.
  std::vector<uchar> buffer;
  SAMP_CHECK(cv::imencode(".png", raw, buffer)) << "WriteDisparity " << path << ": PNG encoding failed";
  WriteBytesAtomically(path, std::string(reinterpret_cast<const char*>(buffer.data()), buffer.size()));
}

}  // namespace samp
