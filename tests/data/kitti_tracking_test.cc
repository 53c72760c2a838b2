#include "libsamp/data/kitti_tracking.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

#include "libsamp/core/error.h"
#include "libsamp/core/pose.h"
#include "libsamp/data/kitti_text.h"
#include "tests/testing/expect_error.h"

namespace samp {
namespace {

using test::ExpectError;
namespace fs = std::filesystem;

class KittiTrackingTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("samp_kitti_tracking_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

Eigen::Isometry3d MakePose(double yaw, double pitch, double roll, const Eigen::Vector3d& t) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitX()) *
                   Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitZ()))
                      .toRotationMatrix();
  pose.translation() = t;
  return pose;
}

// A KITTI-like calibration: camera 2 6 cm right of camera 0 (and 2.7 mm
// ahead), a slightly rotated rectification, the velodyne and IMU axes
// (x forward, y left, z up) and their lever arms.
KittiTrackingCalibration KittiLikeCalibration() {
  KittiTrackingCalibration c;
  Eigen::Matrix3d k;
  k << 721.5377, 0, 609.5593, 0, 721.5377, 172.854, 0, 0, 1;
  const Eigen::Vector3d t[4] = {{0, 0, 0}, {-0.5372, 0, 0}, {0.0599, -0.0003, 0.0027}, {-0.4731, 0.0024, 0.0037}};
  for (int i = 0; i < 4; ++i) {
    c.p[i].leftCols<3>() = k;
    c.p[i].col(3) = k * t[i];
  }
  c.rect = Eigen::AngleAxisd(0.01, Eigen::Vector3d(0.3, 1, 0.2).normalized()).toRotationMatrix();
  Eigen::Matrix3d camera_from_velo_axes;  // x right = -y_velo, y down = -z_velo, z forward = x_velo
  camera_from_velo_axes << 0, -1, 0, 0, 0, -1, 1, 0, 0;
  c.cam0_from_velo.linear() = Eigen::AngleAxisd(0.004, Eigen::Vector3d::UnitX()).toRotationMatrix() * camera_from_velo_axes;
  c.cam0_from_velo.translation() = Eigen::Vector3d(-0.004, -0.076, -0.272);
  c.velo_from_imu.linear() = Eigen::AngleAxisd(0.002, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  c.velo_from_imu.translation() = Eigen::Vector3d(-0.81, 0.32, -0.80);
  return c;
}

double RotationDeg(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Eigen::AngleAxisd(a.transpose() * b).angle() * 180.0 / kPi;
}

// The devkit's maths on poses known by hand: an IMU heading east (yaw 0)
// that moves 10 m east, then turns 90 deg left on the spot.
TEST_F(KittiTrackingTest, OxtsGiveTheKnownImuPoses) {
  const double lat0 = 49.0, lon0 = 8.4;
  const double scale = std::cos(lat0 * kPi / 180.0);
  // 10 m east at Mercator scale s: d lon = 10 / (s r pi / 180).
  const double dlon = 10.0 / (scale * 6378137.0 * kPi / 180.0);
  std::vector<OxtsRecord> records(3);
  records[0].lat_deg = lat0, records[0].lon_deg = lon0, records[0].alt = 100;
  records[1] = records[0];
  records[1].lon_deg += dlon;
  records[2] = records[1];
  records[2].yaw = kPi / 2;
  const std::vector<Eigen::Isometry3d> imu = ImuPosesFromOxts(records);
  ASSERT_EQ(imu.size(), 3u);
  EXPECT_TRUE(imu[0].isApprox(Eigen::Isometry3d::Identity(), 1e-12));
  EXPECT_NEAR((imu[1].translation() - Eigen::Vector3d(10, 0, 0)).norm(), 0.0, 1e-6);
  EXPECT_LT(RotationDeg(imu[1].linear(), Eigen::Matrix3d::Identity()), 1e-9);
  // Turned left: the IMU's x axis (forward) points north = world y.
  EXPECT_NEAR((imu[2].linear().col(0) - Eigen::Vector3d(0, 1, 0)).norm(), 0.0, 1e-12);

  // Through a calibration with the KITTI axes (camera z forward = IMU x) and
  // no lever arms: the camera moves 10 m along its own z, then turns left.
  KittiTrackingCalibration c;
  Eigen::Matrix3d k;
  k << 700, 0, 600, 0, 700, 180, 0, 0, 1;
  for (int i = 0; i < 4; ++i) c.p[i] << k, Eigen::Vector3d::Zero();
  c.cam0_from_velo.linear() << 0, -1, 0, 0, 0, -1, 1, 0, 0;
  const std::vector<Eigen::Isometry3d> cam = CameraPosesFromOxts(records, c);
  EXPECT_NEAR((cam[1].translation() - Eigen::Vector3d(0, 0, 10)).norm(), 0.0, 1e-6);
  // After the left turn the camera's z (forward) points to world -x (left of the start).
  EXPECT_NEAR((cam[2].linear().col(2) - Eigen::Vector3d(-1, 0, 0)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((cam[2].translation() - Eigen::Vector3d(0, 0, 10)).norm(), 0.0, 1e-6);

  // With lever arms the camera turns about the IMU: its centre moves on a
  // circle around the IMU, by R p - p (p = camera centre in IMU frame 0).
  c = KittiLikeCalibration();
  const std::vector<Eigen::Isometry3d> lever = CameraPosesFromOxts(records, c);
  const Eigen::Isometry3d camera_from_imu = c.Camera2FromImu();
  const Eigen::Vector3d p = camera_from_imu.inverse().translation();  // camera centre, IMU frame
  const Eigen::Vector3d expected_in_imu0 = imu[2] * p;
  const Eigen::Vector3d expected = camera_from_imu * expected_in_imu0;
  EXPECT_NEAR((lever[2].translation() - expected).norm(), 0.0, 1e-6);
  // Independently: turning 90 deg on the spot moves the camera centre by
  // sqrt(2) times its horizontal distance from the IMU.
  EXPECT_NEAR((lever[2].translation() - lever[1].translation()).norm(), std::sqrt(2.0) * p.head<2>().norm(), 1e-6);
  EXPECT_GT(p.head<2>().norm(), 0.5);
}

// Camera poses samp knows -> oxts (written and read back) -> the same poses,
// with the world moved to camera 2 of frame 0.
TEST_F(KittiTrackingTest, OxtsRoundTripGivesTheCameraPoses) {
  const KittiTrackingCalibration c = KittiLikeCalibration();
  WriteKittiTrackingCalibration(Path("calib.txt"), c);
  const KittiTrackingCalibration read = ReadKittiTrackingCalibration(Path("calib.txt"));
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(read.p[i].isApprox(c.p[i], 1e-15));
  EXPECT_TRUE(read.Camera2FromImu().isApprox(c.Camera2FromImu(), 1e-14));
  EXPECT_NEAR((read.Camera2FromRectified0() - Eigen::Vector3d(0.0599, -0.0003, 0.0027)).norm(), 0.0, 1e-12);

  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Eigen::Isometry3d> world_from_camera;
  const Eigen::Isometry3d start = MakePose(2.0, 0.05, -0.03, Eigen::Vector3d(120, -3, 4000));
  double heading = 0.0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  for (int k = 0; k < 200; ++k) {  // a drive of ~2 km with turns, hills and sway
    heading += 0.03 * u(rng);
    position += 10.0 * Eigen::Vector3d(std::sin(heading), 0.02 * u(rng), std::cos(heading));
    world_from_camera.push_back(start * MakePose(heading, 0.03 * u(rng), 0.02 * u(rng), position));
  }
  for (const OxtsOrigin origin : {OxtsOrigin(), OxtsOrigin{-33.9, 151.2, 40.0, 0.02, -0.01, -2.5}}) {
    WriteOxts(Path("oxts.txt"), OxtsFromCameraPoses(world_from_camera, c, origin, 10.0));
    const std::vector<OxtsRecord> records = ReadOxts(Path("oxts.txt"));
    ASSERT_EQ(records.size(), world_from_camera.size());
    EXPECT_NEAR(records[0].lat_deg, origin.lat_deg, 1e-12);
    const std::vector<Eigen::Isometry3d> poses = CameraPosesFromOxts(records, read);
    double max_mm = 0, max_deg = 0;
    for (size_t k = 0; k < poses.size(); ++k) {
      const Eigen::Isometry3d expected = world_from_camera[0].inverse() * world_from_camera[k];
      max_mm = std::max(max_mm, 1e3 * (poses[k].translation() - expected.translation()).norm());
      max_deg = std::max(max_deg, RotationDeg(poses[k].linear(), expected.linear()));
    }
    EXPECT_LT(max_mm, 1e-3) << "lat " << origin.lat_deg;   // a micrometre over 2 km
    EXPECT_LT(max_deg, 1e-8) << "lat " << origin.lat_deg;
    // The velocity columns: about 10 m per frame at 10 Hz.
    EXPECT_NEAR(records[100].rest[2], 100.0, 5.0);  // vf, m/s
  }
}

TEST_F(KittiTrackingTest, CalibrationAcceptsBothSpellingsAndNamesWhatIsMissing) {
  const KittiTrackingCalibration c = KittiLikeCalibration();
  WriteKittiTrackingCalibration(Path("calib.txt"), c);
  // The object benchmark's spelling (colons, R0_rect, Tr_velo_to_cam, Tr_imu_to_velo).
  std::ifstream in(Path("calib.txt"));
  std::ofstream out(Path("object.txt"));
  for (std::string line; std::getline(in, line);) {
    for (const auto& [from, to] : {std::pair<std::string, std::string>{"R_rect ", "R0_rect: "},
                                   {"Tr_velo_cam ", "Tr_velo_to_cam: "},
                                   {"Tr_imu_velo ", "Tr_imu_to_velo: "}})
      if (line.rfind(from, 0) == 0) line = to + line.substr(from.size());
    out << line << "\n";
  }
  out.close();
  EXPECT_TRUE(ReadKittiTrackingCalibration(Path("object.txt")).Camera2FromImu().isApprox(c.Camera2FromImu(), 1e-14));

  // Without Tr_imu_velo.
  {
    std::ifstream src(Path("calib.txt"));
    std::ofstream dst(Path("no_imu.txt"));
    for (std::string line; std::getline(src, line);)
      if (line.rfind("Tr_imu_velo", 0) != 0) dst << line << "\n";
  }
  ExpectError([&] { ReadKittiTrackingCalibration(Path("no_imu.txt")); },
              {"no_imu.txt: no Tr_imu_velo line", "IMU -> velodyne"});
  std::ofstream(Path("short.txt")) << "P0: 1 0 0 0 0 1 0 0 0 0 1\n";
  ExpectError([&] { ReadKittiTrackingCalibration(Path("short.txt")); }, {"short.txt:1: P0 has 11 numbers, expected 12"});
  std::ofstream(Path("nan.txt")) << "P2: 700 0 600 0 0 700 nan 0 0 0 1 0\n";
  ExpectError([&] { ReadKittiTrackingCalibration(Path("nan.txt")); }, {"nan.txt:1: P2 'nan' is not a finite number"});
  {
    std::ifstream src(Path("calib.txt"));
    std::ofstream dst(Path("skew.txt"));
    for (std::string line; std::getline(src, line);)
      dst << (line.rfind("R_rect", 0) == 0 ? "R_rect 1 0 0 0 1 0 0 0.1 1" : line) << "\n";
  }
  ExpectError([&] { ReadKittiTrackingCalibration(Path("skew.txt")); }, {"skew.txt:5: R_rect", "not a rotation"});
}

TEST_F(KittiTrackingTest, OxtsErrorsNameFileAndLine) {
  std::string line = "49.0 8.4 100 0 0 0.5";
  for (int k = 0; k < 24; ++k) line += " 0";
  std::ofstream(Path("short.txt")) << line << "\n" << line.substr(0, line.size() - 2) << "\n";
  ExpectError([&] { ReadOxts(Path("short.txt")); }, {"short.txt:2: 29 numbers, expected 30"});
  std::ofstream(Path("nan.txt")) << line << "\n" << "49.0 nan" << line.substr(8) << "\n";
  ExpectError([&] { ReadOxts(Path("nan.txt")); }, {"nan.txt:2: lon 'nan' is not a finite number"});
  std::ofstream(Path("gap.txt")) << line << "\n\n" << line << "\n";
  ExpectError([&] { ReadOxts(Path("gap.txt")); }, {"gap.txt:2: blank line before the last record"});
  std::ofstream(Path("pole.txt")) << "89.5" << line.substr(4) << "\n";
  ExpectError([&] { ReadOxts(Path("pole.txt")); }, {"pole.txt:1: latitude 89.5"});
  std::ofstream(Path("ok.txt")) << line << "\n" << line << "\n\n";
  EXPECT_EQ(ReadOxts(Path("ok.txt")).size(), 2u);  // blank lines at the end
  ExpectError([&] { ReadOxts(Path("missing.txt")); }, {"cannot open oxts file", "missing.txt"});
}

TEST_F(KittiTrackingTest, LayoutPathsAndSequenceLists) {
  const KittiTrackingLayout layout(Path("training"), "0004");
  EXPECT_EQ(layout.LeftImage(12), Path("training") + "/image_02/0004/000012.png");
  EXPECT_EQ(layout.RightImage(0), Path("training") + "/image_03/0004/000000.png");
  EXPECT_EQ(layout.Calibration(), Path("training") + "/calib/0004.txt");
  EXPECT_EQ(layout.Oxts(), Path("training") + "/oxts/0004.txt");
  EXPECT_EQ(layout.Labels(), Path("training") + "/label_02/0004.txt");
  EXPECT_EQ(KittiTrackingLayout::FrameOfFileName("/x/000153.png", ".png"), 153);
  EXPECT_EQ(KittiTrackingLayout::FrameOfFileName("/x/0004_01.png", ".png"), -1);
  EXPECT_EQ(KittiTrackingLayout::FrameOfFileName("/x/1234567.png", ".png"), -1);

  for (const char* name : {"0004", "0011", "0000"}) fs::create_directories(dir_ / "training" / "image_02" / name);
  const std::vector<std::string> all = KittiTrackingSequenceFolders(Path("training"), "all");
  ASSERT_EQ(all.size(), 3u);
  EXPECT_EQ(all[0], Path("training") + "/image_02/0000");
  const std::vector<std::string> some = KittiTrackingSequenceFolders(Path("training"), "4, 0011");
  ASSERT_EQ(some.size(), 2u);
  EXPECT_EQ(some[0], layout.LeftImageFolder());
  ExpectError([&] { KittiTrackingSequenceFolders(Path("training"), "0004,0007"); }, {"has no sequence 0007"});
  ExpectError([&] { KittiTrackingSequenceFolders(Path("training"), "4,0004"); }, {"lists 0004 twice"});
  ExpectError([&] { KittiTrackingSequenceFolders(Path("nothing"), "all"); }, {"has no image_02/ folder"});

  KittiTrackingLayout found("", "");
  ASSERT_TRUE(KittiTrackingLayout::FromSequenceFolder(layout.LeftImageFolder() + "/", &found));
  EXPECT_EQ(found.root(), Path("training"));
  EXPECT_EQ(found.name(), "0004");
  EXPECT_FALSE(KittiTrackingLayout::FromSequenceFolder(Path("training"), nullptr));
  // samp's layout inside an image_02 folder (it has calib/) is samp's.
  fs::create_directories(dir_ / "training" / "image_02" / "0004" / "calib");
  EXPECT_FALSE(KittiTrackingLayout::FromSequenceFolder(layout.LeftImageFolder(), nullptr));
}

// The one parser of --sequence lists, for KITTI tracking (4 digits) and the
// 6-digit layouts.
TEST(SequenceListTest, TrimsPadsAndRejectsEmptyAndRepeatedNames) {
  EXPECT_EQ(kitti_text::ParseSequenceList(" 4, 0011 ,abc", 4), (std::vector<std::string>{"0004", "0011", "abc"}));
  EXPECT_EQ(kitti_text::ParseSequenceList("46,000047", 6), (std::vector<std::string>{"000046", "000047"}));
  ExpectError([] { kitti_text::ParseSequenceList("4,,5", 4); }, {"--sequence '4,,5': empty sequence name"});
  ExpectError([] { kitti_text::ParseSequenceList("46,000046", 6); }, {"--sequence lists 000046 twice"});
  ExpectError([] { kitti_text::ParseSequenceList("", 4); }, {"--sequence is empty", "0004,0011"});
  ExpectError([] { kitti_text::ParseSequenceList("", 6); }, {"000004,000011"});
}

TEST(MoveLabelTest, MovesAndRecomputesAlpha) {
  ObjectLabel label;
  label.position = Eigen::Vector3d(1, 1.6, 10);
  label.rotation_y = 0.3;
  label.alpha = 0.3 - std::atan2(1.0, 10.0);
  const ObjectLabel same = MoveLabel(label, Eigen::Vector3d::Zero());
  EXPECT_EQ(same.alpha, label.alpha);
  const ObjectLabel moved = MoveLabel(label, Eigen::Vector3d(-0.06, 0, 0.0027));
  EXPECT_NEAR(moved.position.x(), 0.94, 1e-12);
  EXPECT_NEAR(moved.alpha, WrapAngle(0.3 - std::atan2(0.94, 10.0027)), 1e-12);
  EXPECT_NEAR(MoveLabel(moved, Eigen::Vector3d(0.06, 0, -0.0027)).alpha, label.alpha, 1e-12);
}

}  // namespace
}  // namespace samp
