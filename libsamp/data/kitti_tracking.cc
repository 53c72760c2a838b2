#include "libsamp/data/kitti_tracking.h"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <map>
#include <sstream>

#include "libsamp/core/atomic_file.h"
#include "libsamp/core/error.h"
#include "libsamp/core/pose.h"
#include "libsamp/data/kitti_io.h"
#include "libsamp/data/kitti_text.h"

namespace samp {
namespace fs = std::filesystem;
using namespace kitti_text;

namespace {

constexpr double kEarthRadius = 6378137.0;  // m, equatorial (the devkit's)
constexpr double kDeg = kPi / 180.0;

// Mercator position (x east, y north) of a latitude/longitude at scale s.
Eigen::Vector2d Mercator(double lat_deg, double lon_deg, double scale) {
  return Eigen::Vector2d(scale * kEarthRadius * lon_deg * kDeg,
                         scale * kEarthRadius * std::log(std::tan((90.0 + lat_deg) * kPi / 360.0)));
}

// Its inverse: (lat, lon) in degrees.
Eigen::Vector2d InverseMercator(const Eigen::Vector2d& xy, double scale) {
  const double lon = xy.x() / (scale * kEarthRadius * kDeg);
  const double lat = 360.0 / kPi * std::atan(std::exp(xy.y() / (scale * kEarthRadius))) - 90.0;
  return Eigen::Vector2d(lat, lon);
}

// R = Rz(yaw) Ry(pitch) Rx(roll).
Eigen::Matrix3d RotationOfAngles(double roll, double pitch, double yaw) {
  return (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

// A rotation within 1e-3 of orthonormal with det > 0, re-orthonormalised.
Eigen::Matrix3d CheckedRotation(const Eigen::Matrix3d& m, const std::string& path, int line, const std::string& key) {
  SAMP_CHECK((m.transpose() * m - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() <= 1e-3 && m.determinant() > 0)
      << At(path, line) << key << ": the 3x3 part is not a rotation (orthonormal within 1e-3, det > 0)";
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  return svd.matrixU() * svd.matrixV().transpose();
}

std::string FormatNumbers(const double* values, int count, int digits) {
  std::ostringstream s;
  s << std::setprecision(digits);
  for (int i = 0; i < count; ++i) s << (i > 0 ? " " : "") << (values[i] == 0.0 ? 0.0 : values[i]);  // no "-0"
  return s.str();
}

std::string FormatRowMajor34(const Eigen::Matrix<double, 3, 4>& m) {
  double v[12];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) v[r * 4 + c] = m(r, c);
  return FormatNumbers(v, 12, 17);
}

Eigen::Matrix<double, 3, 4> Matrix34(const Eigen::Isometry3d& t) { return t.matrix().topRows<3>(); }

}  // namespace

KittiTrackingLayout::KittiTrackingLayout(std::string root, std::string name)
    : root_(std::move(root)), name_(std::move(name)) {}

std::string KittiTrackingLayout::LeftImageFolder() const { return (fs::path(root_) / kLeftImageFolder / name_).string(); }
std::string KittiTrackingLayout::RightImageFolder() const {
  return (fs::path(root_) / kRightImageFolder / name_).string();
}
std::string KittiTrackingLayout::LeftImage(int frame) const {
  return (fs::path(LeftImageFolder()) / FrameFileName(frame, ".png")).string();
}
std::string KittiTrackingLayout::RightImage(int frame) const {
  return (fs::path(RightImageFolder()) / FrameFileName(frame, ".png")).string();
}
std::string KittiTrackingLayout::Calibration() const {
  return (fs::path(root_) / kCalibrationFolder / (name_ + ".txt")).string();
}
std::string KittiTrackingLayout::Oxts() const { return (fs::path(root_) / kOxtsFolder / (name_ + ".txt")).string(); }
std::string KittiTrackingLayout::Labels() const { return (fs::path(root_) / kLabelFolder / (name_ + ".txt")).string(); }

std::string KittiTrackingLayout::FrameFileName(int frame, const std::string& extension) {
  SAMP_CHECK(frame >= 0 && frame <= 999999) << "KITTI tracking frame " << frame << " is not in 0..999999";
  std::ostringstream s;
  s << std::setw(6) << std::setfill('0') << frame << extension;
  return s.str();
}

int KittiTrackingLayout::FrameOfFileName(const std::string& path, const std::string& extension) {
  const std::string file_name = fs::path(path).filename().string();
  if (file_name.size() <= extension.size() || file_name.size() > extension.size() + 6) return -1;
  if (file_name.compare(file_name.size() - extension.size(), extension.size(), extension) != 0) return -1;
  const std::string digits = file_name.substr(0, file_name.size() - extension.size());
  for (const char c : digits)
    if (c < '0' || c > '9') return -1;
  return std::stoi(digits);
}

bool KittiTrackingLayout::FromSequenceFolder(const std::string& folder, KittiTrackingLayout* layout) {
  fs::path path = fs::path(folder).lexically_normal();
  if (!path.has_filename() && path.has_parent_path()) path = path.parent_path();  // "…/0004/"
  const fs::path parent = path.parent_path();
  if (path.filename().empty() || parent.filename() != kLeftImageFolder) return false;
  std::error_code error;
  if (fs::is_directory(path / "calib", error)) return false;  // samp's layout
  if (layout != nullptr) {
    const fs::path root = parent.parent_path();
    *layout = KittiTrackingLayout(root.empty() ? std::string(".") : root.string(), path.filename().string());
  }
  return true;
}

std::vector<std::string> KittiTrackingSequenceFolders(const std::string& root, const std::string& sequences) {
  std::error_code error;
  const fs::path images = fs::path(root) / KittiTrackingLayout::kLeftImageFolder;
  SAMP_CHECK(fs::is_directory(images, error))
      << "KITTI tracking root " << root << " has no image_02/ folder (give the training or testing folder)";
  std::vector<std::string> names;
  if (sequences == "all") {
    for (const fs::directory_entry& entry : fs::directory_iterator(images))
      if (entry.is_directory()) names.push_back(entry.path().filename().string());
    std::sort(names.begin(), names.end());
    SAMP_CHECK(!names.empty()) << images.string() << ": no sequence folders";
  } else {
    names = kitti_text::ParseSequenceList(sequences, 4);
  }
  std::vector<std::string> folders;
  for (const std::string& name : names) {
    const KittiTrackingLayout layout(root, name);
    SAMP_CHECK(fs::is_directory(layout.LeftImageFolder(), error))
        << "KITTI tracking root " << root << " has no sequence " << name << " (no " << layout.LeftImageFolder()
        << ")";
    folders.push_back(layout.LeftImageFolder());
  }
  return folders;
}

Eigen::Vector3d KittiTrackingCalibration::Camera2FromRectified0() const {
  const Eigen::Matrix3d k = p[2].leftCols<3>();
  return k.inverse() * p[2].col(3);
}

Eigen::Isometry3d KittiTrackingCalibration::Camera2FromImu() const {
  Eigen::Isometry3d cam2_from_rect0 = Eigen::Isometry3d::Identity();
  cam2_from_rect0.translation() = Camera2FromRectified0();
  Eigen::Isometry3d rect0_from_cam0 = Eigen::Isometry3d::Identity();
  rect0_from_cam0.linear() = rect;
  return cam2_from_rect0 * rect0_from_cam0 * cam0_from_velo * velo_from_imu;
}

KittiTrackingCalibration ReadKittiTrackingCalibration(const std::string& path) {
  // Key (without colon) -> which entry; several spellings per entry.
  const std::map<std::string, int> entry_of = {{"P0", 0},          {"P1", 1},          {"P2", 2},
                                               {"P3", 3},          {"R_rect", 4},      {"R0_rect", 4},
                                               {"Tr_velo_cam", 5}, {"Tr_velo_to_cam", 5}, {"Tr_imu_velo", 6},
                                               {"Tr_imu_to_velo", 6}};
  const char* names[7] = {"P0", "P1", "P2", "P3", "R_rect", "Tr_velo_cam", "Tr_imu_velo"};
  const char* meaning[7] = {"camera 0 projection", "camera 1 projection", "camera 2 (left colour) projection",
                            "camera 3 (right colour) projection", "rectifying rotation of camera 0",
                            "velodyne -> camera 0", "IMU -> velodyne, needed for the ego poses from oxts/"};
  std::array<std::vector<double>, 7> values;
  std::array<int, 7> line_of{};
  ForEachLine(path, "calibration", [&](int n, const std::string& line) {
    const std::vector<std::string> tokens = Tokenize(line);
    if (tokens.empty()) return;
    std::string key = tokens[0];
    if (!key.empty() && key.back() == ':') key.pop_back();
    const auto it = entry_of.find(key);
    if (it == entry_of.end()) return;  // other entries (R_rect_02, ...) are not used
    const int e = it->second;
    SAMP_CHECK(line_of[e] == 0) << At(path, n) << names[e] << " given twice (first on line " << line_of[e] << ")";
    const size_t expected = e == 4 ? 9 : 12;
    SAMP_CHECK(tokens.size() == expected + 1)
        << At(path, n) << key << " has " << tokens.size() - 1 << " numbers, expected " << expected;
    for (size_t k = 1; k < tokens.size(); ++k) {
      const double v = ParseDouble(tokens[k], path, n, names[e]);
      SAMP_CHECK(std::abs(v) <= 1e9) << At(path, n) << names[e] << " entry " << k - 1 << " = " << v
                                     << " is not a plausible calibration value";
      values[e].push_back(v);
    }
    line_of[e] = n;
  });
  for (int e = 0; e < 7; ++e)
    SAMP_CHECK(line_of[e] > 0) << path << ": no " << names[e] << " line (" << meaning[e] << ")";
  KittiTrackingCalibration c;
  for (int i = 0; i < 4; ++i) {
    for (int k = 0; k < 12; ++k) c.p[i](k / 4, k % 4) = values[i][k];
    const Eigen::Matrix3d k = c.p[i].leftCols<3>();
    SAMP_CHECK(k(0, 0) > 0 && k(1, 1) > 0 && std::abs(k(2, 2) - 1.0) < 1e-9 && k(1, 0) == 0 && k(2, 0) == 0 &&
               k(2, 1) == 0)
        << At(path, line_of[i]) << names[i] << ": the left 3x3 block is not a camera matrix [fx 0 cx; 0 fy cy; 0 0 1]";
  }
  Eigen::Matrix3d rect;
  for (int k = 0; k < 9; ++k) rect(k / 3, k % 3) = values[4][k];
  c.rect = CheckedRotation(rect, path, line_of[4], "R_rect");
  for (int e = 5; e <= 6; ++e) {
    Eigen::Matrix3d r;
    Eigen::Vector3d t;
    for (int k = 0; k < 12; ++k) (k % 4 == 3 ? t[k / 4] : r(k / 4, k % 4)) = values[e][k];
    Eigen::Isometry3d& transform = e == 5 ? c.cam0_from_velo : c.velo_from_imu;
    transform.linear() = CheckedRotation(r, path, line_of[e], names[e]);
    transform.translation() = t;
    SAMP_CHECK(t.norm() <= 100.0) << At(path, line_of[e]) << names[e] << ": translation of " << t.norm()
                                  << " m between sensors of one car is not plausible";
  }
  return c;
}

KittiTrackingCalibration MakeKittiTrackingCalibration(const StereoCalibration& stereo) {
  const PinholeCamera& cam = stereo.camera;
  Eigen::Matrix3d k;
  k << cam.fx, 0, cam.cx, 0, cam.fy, cam.cy, 0, 0, 1;
  const Eigen::Vector3d t2(0.06, 0.0, 0.0027);
  const Eigen::Vector3d right(stereo.baseline, 0.0, 0.0);
  const Eigen::Vector3d t[4] = {Eigen::Vector3d::Zero(), -right, t2, t2 - right};
  KittiTrackingCalibration c;
  for (int i = 0; i < 4; ++i) c.p[i] << k, k * t[i];
  c.rect = Eigen::AngleAxisd(0.5 * kDeg, Eigen::Vector3d(0.2, 1.0, 0.1).normalized()).toRotationMatrix();
  Eigen::Matrix3d camera_axes_from_velo;  // x right = -y_velo, y down = -z_velo, z forward = x_velo
  camera_axes_from_velo << 0, -1, 0, 0, 0, -1, 1, 0, 0;
  c.cam0_from_velo.linear() = Eigen::AngleAxisd(0.3 * kDeg, Eigen::Vector3d::UnitX()).toRotationMatrix() *
                              camera_axes_from_velo;
  c.cam0_from_velo.translation() = Eigen::Vector3d(-0.004, -0.076, -0.272);
  c.velo_from_imu.linear() = Eigen::AngleAxisd(0.1 * kDeg, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  c.velo_from_imu.translation() = Eigen::Vector3d(-0.81, 0.32, -0.80);
  return c;
}

void WriteKittiTrackingCalibration(const std::string& path, const KittiTrackingCalibration& calibration) {
  std::ostringstream s;
  for (int i = 0; i < 4; ++i) s << 'P' << i << ": " << FormatRowMajor34(calibration.p[i]) << '\n';
  double rect[9];
  for (int k = 0; k < 9; ++k) rect[k] = calibration.rect(k / 3, k % 3);
  s << "R_rect " << FormatNumbers(rect, 9, 17) << '\n';
  s << "Tr_velo_cam " << FormatRowMajor34(Matrix34(calibration.cam0_from_velo)) << '\n';
  s << "Tr_imu_velo " << FormatRowMajor34(Matrix34(calibration.velo_from_imu)) << '\n';
  WriteTextFileAtomically(path, s.str());
}

std::vector<OxtsRecord> ReadOxts(const std::string& path) {
  std::vector<OxtsRecord> records;
  int blank_line = 0;
  ForEachLine(path, "oxts", [&](int n, const std::string& line) {
    if (IsBlank(line)) {
      if (blank_line == 0) blank_line = n;
      return;
    }
    SAMP_CHECK(blank_line == 0) << At(path, blank_line)
                                << "blank line before the last record (line k is frame k - 1: a frame without "
                                   "its GPS/IMU record)";
    const std::vector<std::string> tokens = Tokenize(line);
    SAMP_CHECK(tokens.size() == 30) << At(path, n) << tokens.size()
                                    << " numbers, expected 30 (lat lon alt roll pitch yaw vn ve vf vl vu ax ay az af "
                                       "al au wx wy wz wf wl wu pos_accuracy vel_accuracy navstat numsats posmode "
                                       "velmode orimode)";
    static const char* kFields[6] = {"lat", "lon", "alt", "roll", "pitch", "yaw"};
    double v[6];
    for (int k = 0; k < 6; ++k) v[k] = ParseDouble(tokens[k], path, n, kFields[k]);
    OxtsRecord r;
    r.lat_deg = v[0], r.lon_deg = v[1], r.alt = v[2], r.roll = v[3], r.pitch = v[4], r.yaw = v[5];
    for (int k = 0; k < 24; ++k) r.rest[k] = ParseDouble(tokens[6 + k], path, n, "oxts value");
    SAMP_CHECK(std::abs(r.lat_deg) <= 85.0) << At(path, n) << "latitude " << r.lat_deg
                                            << " deg is beyond +-85 deg (Mercator)";
    SAMP_CHECK(std::abs(r.lon_deg) <= 180.0) << At(path, n) << "longitude " << r.lon_deg << " deg is beyond +-180";
    SAMP_CHECK(std::abs(r.alt) <= 1e4) << At(path, n) << "altitude " << r.alt << " m is not plausible";
    for (const double angle : {r.roll, r.pitch, r.yaw})
      SAMP_CHECK(std::abs(angle) <= 2 * kPi) << At(path, n) << "angle " << angle
                                             << " is beyond +-2 pi (roll, pitch and yaw are radians)";
    records.push_back(r);
  });
  return records;
}

void WriteOxts(const std::string& path, const std::vector<OxtsRecord>& records) {
  std::string text;
  for (const OxtsRecord& r : records) {
    double v[30] = {r.lat_deg, r.lon_deg, r.alt, r.roll, r.pitch, r.yaw};
    std::copy(r.rest.begin(), r.rest.end(), v + 6);
    for (const double x : v) SAMP_CHECK(std::isfinite(x)) << "WriteOxts " << path << ": a non-finite value";
    text += FormatNumbers(v, 30, 17) + "\n";
  }
  WriteTextFileAtomically(path, text);
}

std::vector<Eigen::Isometry3d> ImuPosesFromOxts(const std::vector<OxtsRecord>& records) {
  std::vector<Eigen::Isometry3d> poses;
  if (records.empty()) return poses;
  const double scale = std::cos(records.front().lat_deg * kDeg);
  Eigen::Isometry3d imu0_from_mercator = Eigen::Isometry3d::Identity();
  for (size_t k = 0; k < records.size(); ++k) {
    const OxtsRecord& r = records[k];
    Eigen::Isometry3d mercator_from_imu = Eigen::Isometry3d::Identity();
    mercator_from_imu.linear() = RotationOfAngles(r.roll, r.pitch, r.yaw);
    mercator_from_imu.translation() << Mercator(r.lat_deg, r.lon_deg, scale), r.alt;
    if (k == 0) imu0_from_mercator = mercator_from_imu.inverse();
    poses.push_back(imu0_from_mercator * mercator_from_imu);
  }
  return poses;
}

std::vector<Eigen::Isometry3d> CameraPosesFromOxts(const std::vector<OxtsRecord>& records,
                                                   const KittiTrackingCalibration& calibration) {
  const Eigen::Isometry3d camera_from_imu = calibration.Camera2FromImu();
  const Eigen::Isometry3d imu_from_camera = camera_from_imu.inverse();
  std::vector<Eigen::Isometry3d> poses;
  for (const Eigen::Isometry3d& imu0_from_imu : ImuPosesFromOxts(records))
    poses.push_back(camera_from_imu * imu0_from_imu * imu_from_camera);
  return poses;
}

std::vector<OxtsRecord> OxtsFromCameraPoses(const std::vector<Eigen::Isometry3d>& world_from_camera,
                                            const KittiTrackingCalibration& calibration, const OxtsOrigin& origin,
                                            double frame_rate_hz) {
  SAMP_CHECK(frame_rate_hz > 0) << "OxtsFromCameraPoses: frame rate must be positive";
  std::vector<OxtsRecord> records;
  if (world_from_camera.empty()) return records;
  const Eigen::Isometry3d camera_from_imu = calibration.Camera2FromImu();
  const double scale = std::cos(origin.lat_deg * kDeg);
  Eigen::Isometry3d mercator_from_imu0 = Eigen::Isometry3d::Identity();
  mercator_from_imu0.linear() = RotationOfAngles(origin.roll, origin.pitch, origin.yaw);
  mercator_from_imu0.translation() << Mercator(origin.lat_deg, origin.lon_deg, scale), origin.alt;
  const Eigen::Isometry3d camera0_from_world = world_from_camera.front().inverse();
  std::vector<Eigen::Isometry3d> mercator_from_imu;
  for (size_t k = 0; k < world_from_camera.size(); ++k) {
    const Eigen::Matrix3d r = world_from_camera[k].linear();
    SAMP_CHECK((r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() <= 1e-6)
        << "OxtsFromCameraPoses: pose " << k << " is not rigid";
    const Eigen::Isometry3d imu0_from_imu =
        camera_from_imu.inverse() * camera0_from_world * world_from_camera[k] * camera_from_imu;
    mercator_from_imu.push_back(mercator_from_imu0 * imu0_from_imu);
  }
  for (size_t k = 0; k < mercator_from_imu.size(); ++k) {
    const Eigen::Matrix3d& r = mercator_from_imu[k].linear();
    const Eigen::Vector3d& t = mercator_from_imu[k].translation();
    SAMP_CHECK(std::abs(r(2, 0)) < 1.0 - 1e-9) << "OxtsFromCameraPoses: pose " << k
                                               << " has a pitch of +-90 deg (Euler angles undefined)";
    OxtsRecord rec;
    const Eigen::Vector2d lat_lon = InverseMercator(t.head<2>(), scale);
    rec.lat_deg = lat_lon[0];
    rec.lon_deg = lat_lon[1];
    rec.alt = t.z();
    rec.pitch = std::asin(-r(2, 0));
    rec.yaw = std::atan2(r(1, 0), r(0, 0));
    rec.roll = std::atan2(r(2, 1), r(2, 2));
    // Velocity by finite differences (central inside, one-sided at the ends).
    const size_t a = k > 0 ? k - 1 : k, b = k + 1 < mercator_from_imu.size() ? k + 1 : k;
    Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
    if (b > a)
      velocity = (mercator_from_imu[b].translation() - mercator_from_imu[a].translation()) * frame_rate_hz /
                 double(b - a);
    const Eigen::Vector3d in_imu = r.transpose() * velocity;  // forward, left, up
    rec.rest.fill(0.0);
    rec.rest[0] = velocity.y();  // vn
    rec.rest[1] = velocity.x();  // ve
    rec.rest[2] = in_imu.x();    // vf
    rec.rest[3] = in_imu.y();    // vl
    rec.rest[4] = in_imu.z();    // vu
    // ax ay az af al au wx wy wz wf wl wu: 0 (rest[5..16]).
    rec.rest[17] = 0.05;  // pos_accuracy, m
    rec.rest[18] = 0.02;  // vel_accuracy, m/s
    rec.rest[19] = 4;     // navstat
    rec.rest[20] = 10;    // numsats
    rec.rest[21] = 5;     // posmode
    rec.rest[22] = 5;     // velmode
    rec.rest[23] = 6;     // orimode
    records.push_back(rec);
  }
  return records;
}

ObjectLabel MoveLabel(const ObjectLabel& label, const Eigen::Vector3d& offset) {
  if (offset.isZero(0.0)) return label;
  ObjectLabel moved = label;
  moved.position += offset;
  if (!SameObjectType(label.type, "DontCare"))
    moved.alpha = WrapAngle(moved.rotation_y - std::atan2(moved.position.x(), moved.position.z()));
  return moved;
}

}  // namespace samp
