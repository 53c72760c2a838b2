#include "libsamp/data/sequence.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <opencv2/imgcodecs.hpp>

#include "libsamp/core/error.h"
#include "tests/testing/expect_error.h"
#include "libsamp/core/log.h"
#include "libsamp/data/detection_files.h"
#include "libsamp/data/kitti_io.h"
#include "libsamp/data/kitti_tracking.h"

namespace samp {
namespace {

using test::ExpectError;

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------
// A tiny synthetic sequence: a box car crossing at ~12 m in front of an ego
// camera that drives forward; road 1.65 m below the camera, a wall at 40 m.

constexpr double kRoadY = 1.65;
constexpr double kWallZ = 40.0;
const Eigen::Vector3d kCarHalf(0.8, 0.75, 2.0);  // half extents x y z, m

StereoCalibration SmallCalibration() {
  StereoCalibration c;
  c.camera.fx = c.camera.fy = 350;
  c.camera.cx = 200;
  c.camera.cy = 75;
  c.camera.width = 400;
  c.camera.height = 150;
  c.baseline = 0.54;
  return c;
}

Eigen::Isometry3d Ego(int frame) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(0, 0, 0.5 * frame);
  return pose;
}

Eigen::Vector3d CarCenterInWorld(int frame) { return Eigen::Vector3d(-2.0 + 0.6 * frame, kRoadY - 0.75, 13.0); }

// Depth along the ray from `origin` (camera frame) through direction `ray`
// (z = 1) and the hit point: box car, road, wall.
double Cast(const Eigen::Vector3d& origin, const Eigen::Vector3d& ray, const Eigen::Vector3d& car_center,
            Eigen::Vector3d* hit) {
  double t_near = -1e9, t_far = 1e9;
  for (int k = 0; k < 3; ++k) {
    const double lo = car_center[k] - kCarHalf[k], hi = car_center[k] + kCarHalf[k];
    if (std::abs(ray[k]) < 1e-12) {
      if (origin[k] < lo || origin[k] > hi) t_near = 1e10;
      continue;
    }
    double t0 = (lo - origin[k]) / ray[k], t1 = (hi - origin[k]) / ray[k];
    if (t0 > t1) std::swap(t0, t1);
    t_near = std::max(t_near, t0);
    t_far = std::min(t_far, t1);
  }
  double t = kWallZ;
  if (t_near <= t_far && t_near > 0) {
    t = t_near;
  } else if (ray.y() > 0 && (kRoadY - origin.y()) / ray.y() < kWallZ) {
    t = (kRoadY - origin.y()) / ray.y();
  }
  *hit = origin + t * ray;
  return t;  // = depth, as ray.z() = 1
}

// Procedural texture (cells of 4 cm) so that SGBM can match.
uint8_t Texture(const Eigen::Vector3d& p_in_world) {
  const long long x = static_cast<long long>(std::floor(p_in_world.x() / 0.04));
  const long long y = static_cast<long long>(std::floor(p_in_world.y() / 0.04));
  const long long z = static_cast<long long>(std::floor(p_in_world.z() / 0.04));
  unsigned long long h = static_cast<unsigned long long>(x * 73856093LL ^ y * 19349663LL ^ z * 83492791LL);
  h ^= h >> 13;
  h *= 0x5bd1e995ULL;
  h ^= h >> 15;
  return static_cast<uint8_t>(40 + h % 176);
}

void RenderFrame(const StereoCalibration& c, int frame, cv::Mat* disparity, cv::Mat* left, cv::Mat* right) {
  const Eigen::Isometry3d ego = Ego(frame);
  const Eigen::Vector3d car = ego.inverse() * CarCenterInWorld(frame);
  *disparity = cv::Mat(c.camera.height, c.camera.width, CV_32FC1);
  *left = cv::Mat(c.camera.height, c.camera.width, CV_8UC1);
  *right = cv::Mat(c.camera.height, c.camera.width, CV_8UC1);
  for (int v = 0; v < c.camera.height; ++v)
    for (int u = 0; u < c.camera.width; ++u) {
      const Eigen::Vector3d ray = c.camera.Ray(u, v);
      Eigen::Vector3d hit;
      const double z = Cast(Eigen::Vector3d::Zero(), ray, car, &hit);
      disparity->at<float>(v, u) = static_cast<float>(c.camera.fx * c.baseline / z);
      left->at<uint8_t>(v, u) = Texture(ego * hit);
      const Eigen::Vector3d right_origin(c.baseline, 0, 0);
      Cast(right_origin, ray, car, &hit);
      right->at<uint8_t>(v, u) = Texture(ego * hit);
    }
}

ObjectLabel CarDetection(const StereoCalibration& c, int frame) {
  const Eigen::Vector3d center = Ego(frame).inverse() * CarCenterInWorld(frame);
  ObjectLabel d;
  d.type = "Car";
  d.height = 2 * kCarHalf.y();
  d.width = 2 * kCarHalf.x();
  d.length = 2 * kCarHalf.z();
  d.position = center + Eigen::Vector3d(0, kCarHalf.y(), 0);
  d.rotation_y = -M_PI / 2;  // length along z
  Eigen::Vector2d lo(1e9, 1e9), hi(-1e9, -1e9);
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d corner = center + Eigen::Vector3d((k & 1 ? 1 : -1) * kCarHalf.x(),
                                                            (k & 2 ? 1 : -1) * kCarHalf.y(),
                                                            (k & 4 ? 1 : -1) * kCarHalf.z());
    const Eigen::Vector2d p = c.camera.Project(corner);
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  d.box_2d << std::max(0.0, lo.x()), std::max(0.0, lo.y()), std::min(c.camera.width - 1.0, hi.x()),
      std::min(c.camera.height - 1.0, hi.y());
  return d;
}

std::string Tag(int frame) { return std::string("000007_0") + std::to_string(frame); }

class SequenceTest : public ::testing::Test {
 protected:
  static constexpr int kFrames = 5;
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("samp_sequence_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name()) / "000007";
    fs::remove_all(dir_.parent_path());
    fs::create_directories(dir_);
    const StereoCalibration c = SmallCalibration();
    WriteCalibration((dir_ / "calib" / "000007.txt").string(), c);
    std::vector<Eigen::Isometry3d> poses;
    for (int t = 0; t < kFrames; ++t) poses.push_back(Ego(t));
    WritePoses((dir_ / "poses" / "000007.txt").string(), poses);
    for (int t = 0; t < kFrames; ++t) {
      cv::Mat disparity, left, right;
      RenderFrame(c, t, &disparity, &left, &right);
      cv::imwrite((dir_ / "image_2").string() + "/" + Tag(t) + ".png", (fs::create_directories(dir_ / "image_2"), left));
      cv::imwrite((dir_ / "image_3").string() + "/" + Tag(t) + ".png", (fs::create_directories(dir_ / "image_3"), right));
      if (t != 3) WriteDisparity((dir_ / "disparity" / (Tag(t) + ".png")).string(), disparity);  // frame 3: SGBM
      if (t != 2) WritePlane((dir_ / "planes" / (Tag(t) + ".txt")).string(), Eigen::Vector4d(0, -1, 0, kRoadY));  // frame 2: RANSAC
      std::vector<ObjectLabel> detections;
      if (t != 1) detections.push_back(CarDetection(c, t));  // missed in frame 1
      ObjectLabel pedestrian = CarDetection(c, t);
      pedestrian.type = "Pedestrian";
      pedestrian.position.x() += 4;
      detections.push_back(pedestrian);  // another type: ignored
      WriteLabels((dir_ / "detections" / (Tag(t) + ".txt")).string(), detections);
    }
  }
  void TearDown() override { fs::remove_all(dir_.parent_path()); }
  fs::path dir_;
};

TEST_F(SequenceTest, ListsTheDirectory) {
  const SequenceFiles files = ListSequence(dir_.string());
  EXPECT_EQ(files.name, "000007");
  ASSERT_EQ(files.frames.size(), static_cast<size_t>(kFrames));
  EXPECT_FALSE(files.poses.empty());
  EXPECT_TRUE(files.frames[3].disparity.empty());
  EXPECT_FALSE(files.frames[3].image_right.empty());
  EXPECT_TRUE(files.frames[2].plane.empty());
  EXPECT_EQ(files.frames[4].frame, 4);
}

TEST_F(SequenceTest, EndToEnd) {
  SequenceOptions options;
  options.stereo.num_disparities = 32;
  SequenceSummary summary;
  const std::vector<Track> tracks = LoadSequenceTracks(dir_.string(), options, &summary);
  ASSERT_EQ(tracks.size(), 1u) << summary.BriefReport();
  const Track& track = tracks[0];
  EXPECT_EQ(track.id, 0);
  EXPECT_EQ(track.sequence, "000007");
  EXPECT_EQ(track.type, "Car");
  EXPECT_NEAR(track.calibration.baseline, 0.54, 1e-9);
  EXPECT_EQ(track.calibration.camera.width, 400);
  EXPECT_EQ(track.calibration.camera.height, 150);
  ASSERT_EQ(track.frames.size(), 4u);  // frame 1 missed
  const std::vector<int> expected_frames = {0, 2, 3, 4};
  for (size_t i = 0; i < track.frames.size(); ++i) {
    const TrackFrame& f = track.frames[i];
    const int t = expected_frames[i];
    SCOPED_TRACE("frame " + std::to_string(t));
    EXPECT_EQ(f.frame, t);
    EXPECT_DOUBLE_EQ(f.time, t / 10.0);
    EXPECT_EQ(f.detection.frame, t);
    EXPECT_EQ(f.detection.track_id, 0);
    EXPECT_TRUE(f.world_from_camera.isApprox(Ego(t), 1e-9));
    // Road plane in world: y = 1.65 (the ego only moves along z).
    EXPECT_NEAR(f.ground_plane_in_world[1], -1.0, t == 2 ? 1e-2 : 1e-9);
    EXPECT_NEAR(f.ground_plane_in_world[3], kRoadY, t == 2 ? 0.03 : 1e-9);
    ASSERT_GT(f.candidate_points_in_world.size(), 500u);
    ASSERT_LE(f.candidate_points_in_world.size(), 5000u);
    // The points lie on the car's box surface (SGBM in frame 3: approximately).
    const Eigen::Vector3d center = CarCenterInWorld(t);
    std::vector<double> outside;
    for (const Eigen::Vector3d& p : f.candidate_points_in_world) {
      const Eigen::Vector3d q = ((p - center).cwiseAbs() - kCarHalf).cwiseMax(0.0);
      outside.push_back(q.norm());
    }
    std::sort(outside.begin(), outside.end());
    EXPECT_LT(outside[outside.size() / 2], t == 3 ? 0.1 : 0.01);
    if (t != 3) {
      EXPECT_LT(outside[outside.size() * 95 / 100], 0.02);
    }
    for (size_t k = 0; k < f.candidate_sigmas.size(); ++k) {
      const double z = 0.54 * 350 / f.candidate_disparities_px[k];
      ASSERT_NEAR(f.candidate_sigmas[k], z * z / (0.54 * 350), 1e-6);
    }
  }
  EXPECT_EQ(summary.name, "000007");
  EXPECT_EQ(summary.num_frames, kFrames);
  EXPECT_TRUE(summary.poses_from_file);
  EXPECT_FALSE(summary.tracks_from_labels);
  EXPECT_EQ(summary.frames_with_estimated_plane, 1);
  EXPECT_EQ(summary.frames_plane_estimation_failed, 0);
  EXPECT_EQ(summary.frames_with_computed_disparity, 1);
  EXPECT_EQ(summary.num_tracks, 1);
  EXPECT_EQ(summary.num_track_frames, 4);
  EXPECT_EQ(summary.num_track_frames_without_points, 0);
  EXPECT_FALSE(summary.BriefReport().empty());
  ASSERT_EQ(summary.messages.size(), 2u);  // the RANSAC plane and the SGBM disparity
}

TEST_F(SequenceTest, TracksFromALabelFileAndFrameRange) {
  const StereoCalibration c = SmallCalibration();
  std::vector<ObjectLabel> labels;
  for (int t = 0; t < kFrames; ++t) {
    ObjectLabel l = CarDetection(c, t);
    l.frame = t;
    l.track_id = 42;
    labels.push_back(l);
  }
  const std::string path = (dir_.parent_path() / "label_02" / "000007.txt").string();
  WriteTrackingLabels(path, labels);
  SequenceOptions options;
  options.tracking_labels_path = path;
  options.first_frame = 1;
  options.last_frame = 2;
  SequenceSummary summary;
  const std::vector<Track> tracks = LoadSequenceTracks(dir_.string(), options, &summary);
  ASSERT_EQ(tracks.size(), 1u);
  EXPECT_EQ(tracks[0].id, 42);
  ASSERT_EQ(tracks[0].frames.size(), 2u);
  EXPECT_EQ(tracks[0].frames[0].frame, 1);
  EXPECT_TRUE(summary.tracks_from_labels);
  EXPECT_EQ(summary.num_frames, 2);
  // A label in a frame the sequence lacks is an error.
  labels[0].frame = 17;
  WriteTrackingLabels(path, labels);
  options.first_frame = options.last_frame = -1;
  EXPECT_THROW(LoadSequenceTracks(dir_.string(), options, nullptr), Error);
}


TEST_F(SequenceTest, StaticCameraWithoutPoses) {
  fs::remove_all(dir_ / "poses");
  SequenceSummary summary;
  const std::vector<Track> tracks = LoadSequenceTracks(dir_.string(), SequenceOptions(), &summary);
  EXPECT_FALSE(summary.poses_from_file);
  // The car drives 0.6 m/frame relative to a moving ego: with a static
  // camera assumed it is still one track, in camera coordinates.
  ASSERT_EQ(tracks.size(), 1u);
  EXPECT_TRUE(tracks[0].frames[1].world_from_camera.isApprox(Eigen::Isometry3d::Identity()));
  EXPECT_NE(summary.messages.front().find("static camera"), std::string::npos);
}

TEST_F(SequenceTest, BadInputNamesTheFile) {
  ExpectError([&] { LoadSequenceTracks((dir_.parent_path() / "nope").string(), SequenceOptions()); }, {"does not exist"});
  // Missing detections file of a frame.
  fs::remove(dir_ / "detections" / (Tag(4) + ".txt"));
  ExpectError([&] { LoadSequenceTracks(dir_.string(), SequenceOptions()); }, {"detections/000007_04.txt"});
  WriteLabels((dir_ / "detections" / (Tag(4) + ".txt")).string(), {});
  // Malformed detection.
  std::ofstream((dir_ / "detections" / (Tag(2) + ".txt")).string()) << "Car 0 0 0 1 2 3 4 1 1 1 0 1.6 -4 0\n";
  ExpectError([&] { LoadSequenceTracks(dir_.string(), SequenceOptions()); }, {"000007_02.txt:1: object at z = -4"});
  // The car again (a lone detection in frame 0 followed by two misses would
  // start no track, and no frame would be read).
  WriteLabels((dir_ / "detections" / (Tag(2) + ".txt")).string(), {CarDetection(SmallCalibration(), 2)});
  // Disparity of the wrong size.
  WriteDisparity((dir_ / "disparity" / (Tag(0) + ".png")).string(), cv::Mat(10, 10, CV_32FC1, cv::Scalar(5)));
  ExpectError([&] { LoadSequenceTracks(dir_.string(), SequenceOptions()); }, {"000007_00.png: disparity is 10x10"});
  fs::remove(dir_ / "disparity" / (Tag(0) + ".png"));
  // Neither disparity nor the right image.
  fs::remove(dir_ / "image_3" / (Tag(0) + ".png"));
  ExpectError([&] { LoadSequenceTracks(dir_.string(), SequenceOptions()); }, {"no image_2/image_3 pair"});
  // Poses too short.
  WritePoses((dir_ / "poses" / "000007.txt").string(), {Eigen::Isometry3d::Identity()});
  ExpectError([&] { LoadSequenceTracks(dir_.string(), SequenceOptions()); }, {"poses/000007.txt: 1 poses"});
  // Missing calibration.
  fs::remove_all(dir_ / "calib");
  ExpectError([&] { LoadSequenceTracks(dir_.string(), SequenceOptions()); }, {"no calib/ folder"});
}

// The sequence reader knows the image size (from image_2/) and checks the
// calibration's principal point against it.
TEST_F(SequenceTest, PrincipalPointOutsideTheImageNamesTheFile) {
  StereoCalibration c = SmallCalibration();
  c.camera.cx = 5000;
  WriteCalibration((dir_ / "calib" / "000007.txt").string(), c);
  ExpectError([&] { LoadSequenceTracks(dir_.string(), SequenceOptions()); }, {"principal point (5000"});
  ExpectError([&] { SequenceReader reader(dir_.string(), SequenceOptions()); }, {"calib/000007.txt:1:"});
}

// A detection without a volume is an error naming its file and number (the
// tracker's message named neither).
TEST_F(SequenceTest, ZeroSizeDetectionNamesItsFile) {
  ObjectLabel flat = CarDetection(SmallCalibration(), 2);
  flat.width = 0;
  WriteLabels((dir_ / "detections" / (Tag(2) + ".txt")).string(), {flat});
  ExpectError([&] { LoadSequenceTracks(dir_.string(), SequenceOptions()); },
              {"detections/000007_02.txt: detection 1 (Car) has a zero size"});
}

// A frame missing in the middle of a sequence is reported (warning and the
// summary's messages, which go to tracks.json), naming the missing frames.
TEST_F(SequenceTest, GapInFrameNumbersIsReported) {
  for (const char* folder : {"image_2", "image_3", "disparity", "detections", "planes"}) {
    for (const char* extension : {".png", ".txt"}) fs::remove(dir_ / folder / (Tag(2) + extension));
  }
  SequenceSummary summary;
  try {
    LoadSequenceTracks(dir_.string(), SequenceOptions(), &summary);
  } catch (const Error&) {
    // The linking across the gap may fail; the listing was reported first.
  }
  bool found = false;
  for (const std::string& message : summary.messages)
    found = found || message == "000007: frame(s) 2 missing (no image, disparity or detection file) between "
                                "frames 1 and 3";
  EXPECT_TRUE(found) << ::testing::PrintToString(summary.messages);
}

TEST_F(SequenceTest, MalformedPlaneNamesTheFile) {
  std::ofstream((dir_ / "planes" / (Tag(0) + ".txt")).string()) << "# Matrix\nWIDTH 4\nHEIGHT 1\n0 -1 0\n";
  ExpectError([&] { LoadSequenceTracks(dir_.string(), SequenceOptions()); }, {"000007_00.txt:4: 3 numbers"});
}

// ---------------------------------------------------------------------------
// The real KITTI frame in ../shared/kitti/000046, when present.

std::string SharedKitti() {
  const char* env = std::getenv("SAMP_SHARED_DIR");
  const std::string shared = env != nullptr ? env : SAMP_SHARED_DIR;
  return shared + "/kitti/000046";
}

// The fixture's sequence in KITTI tracking's own layout: the images copied to
// image_02/0007/<ffffff>.png, a calibration with all matrices (camera 2
// 6 cm right of and 2.7 mm ahead of camera 0, KITTI's lever arms), oxts from
// the ego poses, the detections as one AB3DMOT file in rectified camera 0.
class KittiTrackingSequenceTest : public SequenceTest {
 protected:
  void SetUp() override {
    SequenceTest::SetUp();
    root_ = dir_.parent_path() / "training";
    const KittiTrackingLayout layout(root_.string(), "0007");
    folder_ = layout.LeftImageFolder();
    fs::create_directories(layout.LeftImageFolder());
    fs::create_directories(layout.RightImageFolder());
    fs::create_directories(root_ / "calib");
    fs::create_directories(root_ / "oxts");
    const StereoCalibration small = SmallCalibration();
    Eigen::Matrix3d k;
    k << small.camera.fx, 0, small.camera.cx, 0, small.camera.fy, small.camera.cy, 0, 0, 1;
    t2_ = Eigen::Vector3d(0.06, -0.0003, 0.0027);
    const Eigen::Vector3d t[4] = {Eigen::Vector3d::Zero(), Eigen::Vector3d(-0.54, 0, 0), t2_,
                                  t2_ - Eigen::Vector3d(small.baseline, 0, 0)};
    for (int i = 0; i < 4; ++i) calibration_.p[i] << k, k * t[i];
    calibration_.rect = Eigen::AngleAxisd(0.01, Eigen::Vector3d::UnitY()).toRotationMatrix();
    calibration_.cam0_from_velo.linear() << 0, -1, 0, 0, 0, -1, 1, 0, 0;
    calibration_.cam0_from_velo.translation() = Eigen::Vector3d(-0.004, -0.076, -0.272);
    calibration_.velo_from_imu.translation() = Eigen::Vector3d(-0.81, 0.32, -0.8);
    WriteKittiTrackingCalibration(layout.Calibration(), calibration_);
    std::vector<Eigen::Isometry3d> poses;
    std::vector<ObjectLabel> detections;
    for (int t = 0; t < kFrames; ++t) {
      poses.push_back(Ego(t));
      fs::copy_file(dir_ / "image_2" / (Tag(t) + ".png"), layout.LeftImage(t));
      fs::copy_file(dir_ / "image_3" / (Tag(t) + ".png"), layout.RightImage(t));
      for (ObjectLabel label : ReadLabels((dir_ / "detections" / (Tag(t) + ".txt")).string())) {
        label.frame = t;
        detections.push_back(MoveLabel(label, -t2_));  // camera 2 -> rectified camera 0
      }
    }
    WriteOxts(layout.Oxts(), OxtsFromCameraPoses(poses, calibration_, OxtsOrigin(), 10.0));
    detections_ = (dir_.parent_path() / "detections" / "0007.txt").string();
    fs::create_directories(fs::path(detections_).parent_path());
    WriteAb3dmotDetections(detections_, detections);
    // samp's layout without disparity/ and planes/: SGBM and RANSAC, as KITTI tracking.
    fs::remove_all(dir_ / "disparity");
    fs::remove_all(dir_ / "planes");
  }
  fs::path root_;
  std::string folder_, detections_;
  KittiTrackingCalibration calibration_;
  Eigen::Vector3d t2_;
};

TEST_F(KittiTrackingSequenceTest, GivesTheTracksOfSampsLayout) {
  SequenceOptions options;
  options.stereo.num_disparities = 32;
  SequenceSummary samp_summary, kitti_summary;
  const std::vector<Track> samp = LoadSequenceTracks(dir_.string(), options, &samp_summary);
  options.detections_path = detections_;
  const SequenceFiles files = ListSequence(folder_);
  EXPECT_EQ(files.layout, SequenceFiles::Layout::kKittiTracking);
  EXPECT_EQ(files.name, "0007");
  ASSERT_EQ(files.frames.size(), size_t(kFrames));
  const std::vector<Track> kitti = LoadSequenceTracks(folder_, options, &kitti_summary);
  EXPECT_EQ(kitti_summary.layout, "kitti-tracking");
  EXPECT_TRUE(kitti_summary.poses_from_file);
  EXPECT_EQ(kitti_summary.frames_with_computed_disparity, samp_summary.frames_with_computed_disparity);
  EXPECT_EQ(kitti_summary.frames_with_estimated_plane, samp_summary.frames_with_estimated_plane);
  ASSERT_EQ(kitti.size(), samp.size());
  ASSERT_EQ(kitti.size(), 1u);
  EXPECT_EQ(kitti[0].sequence, "0007");
  EXPECT_NEAR(kitti[0].calibration.baseline, samp[0].calibration.baseline, 1e-12);
  ASSERT_EQ(kitti[0].frames.size(), samp[0].frames.size());
  for (size_t i = 0; i < samp[0].frames.size(); ++i) {
    const TrackFrame &a = samp[0].frames[i], &b = kitti[0].frames[i];
    SCOPED_TRACE("frame " + std::to_string(a.frame));
    EXPECT_EQ(a.frame, b.frame);
    // Camera 2 of frame 0 is the world of both; the oxts round trip (15
    // significant digits: ~1e-8 m at KITTI's latitude) and
    // AB3DMOT's 6 decimals are all that differs.
    EXPECT_LT((a.world_from_camera.matrix() - b.world_from_camera.matrix()).cwiseAbs().maxCoeff(), 1e-7);
    EXPECT_LT((a.detection.position - b.detection.position).norm(), 2e-6);
    EXPECT_NEAR(a.detection.rotation_y, b.detection.rotation_y, 1e-6);
    EXPECT_LT((a.ground_plane_in_world - b.ground_plane_in_world).norm(), 1e-6);
    ASSERT_EQ(a.candidate_points_in_world.size(), b.candidate_points_in_world.size());
    for (size_t k = 0; k < a.candidate_points_in_world.size(); ++k)
      ASSERT_LT((a.candidate_points_in_world[k] - b.candidate_points_in_world[k]).norm(), 1e-6);
  }
  // Written labels go back to rectified camera 0.
  EXPECT_LT((kitti_summary.label_frame_offset + t2_).norm(), 1e-12);
  std::vector<ObjectLabel> labels = {kitti[0].frames[0].detection};
  LabelsInLayoutFrame(kitti_summary, &labels);
  EXPECT_LT((labels[0].position - (samp[0].frames[0].detection.position - t2_)).norm(), 2e-6);
  std::vector<ObjectLabel> samp_labels = {samp[0].frames[0].detection};
  LabelsInLayoutFrame(samp_summary, &samp_labels);
  EXPECT_EQ(samp_labels[0].position, samp[0].frames[0].detection.position);

  // The same detections as a KITTI tracking result file in a folder
  // (<seq>.txt), and a frame range.
  std::vector<ObjectLabel> tracking = ReadAb3dmotDetections(detections_);
  for (ObjectLabel& label : tracking) label.track_id = 3;
  const fs::path results = dir_.parent_path() / "results";
  WriteTrackingLabels((results / "0007.txt").string(), tracking);
  options.detections_path = results.string();
  options.first_frame = 2;
  options.last_frame = 4;
  const std::vector<Track> ranged = LoadSequenceTracks(folder_, options, &kitti_summary);
  ASSERT_EQ(ranged.size(), 1u);
  ASSERT_EQ(ranged[0].frames.size(), 3u);
  EXPECT_EQ(ranged[0].frames[0].frame, 2);
  EXPECT_LT((ranged[0].frames[0].detection.position - samp[0].frames[1].detection.position).norm(), 2e-4);
}

TEST_F(KittiTrackingSequenceTest, BadInputNamesFileAndLine) {
  SequenceOptions options;
  options.stereo.num_disparities = 32;
  // No detections given.
  ExpectError([&] { LoadSequenceTracks(folder_, options); }, {"has no detections", "--detections"});
  options.detections_path = detections_;
  // Oxts shorter than the sequence.
  const KittiTrackingLayout layout(root_.string(), "0007");
  std::vector<Eigen::Isometry3d> poses = {Ego(0), Ego(1), Ego(2)};
  WriteOxts(layout.Oxts(), OxtsFromCameraPoses(poses, calibration_, OxtsOrigin(), 10.0));
  ExpectError([&] { LoadSequenceTracks(folder_, options); }, {"oxts/0007.txt:4: no GPS/IMU record for frame 3"});
  fs::remove(layout.Oxts());
  ExpectError([&] { LoadSequenceTracks(folder_, options); }, {"missing", "oxts/0007.txt"});
  poses.push_back(Ego(3));
  poses.push_back(Ego(4));
  WriteOxts(layout.Oxts(), OxtsFromCameraPoses(poses, calibration_, OxtsOrigin(), 10.0));
  // A detection line of 14 fields (the file has 9 good lines).
  const std::vector<ObjectLabel> good = ReadAb3dmotDetections(detections_);
  ASSERT_EQ(good.size(), 9u);
  std::ofstream(detections_, std::ios::app) << "4,2,10,20,30,40,0.5,1.5,1.6,4,1,1.6,12,0.1\n";
  ExpectError([&] { LoadSequenceTracks(folder_, options); }, {"0007.txt:10: 14 fields, expected 15"});
  // A detection in a frame the sequence does not have.
  std::vector<ObjectLabel> late = good;
  late.back().frame = 9;
  WriteAb3dmotDetections(detections_, late);
  ExpectError([&] { LoadSequenceTracks(folder_, options); }, {"0007.txt: a detection in frame 9", "frames 0..4"});
  WriteAb3dmotDetections(detections_, good);
  EXPECT_EQ(LoadSequenceTracks(folder_, options).size(), 1u);
  // A calibration without Tr_imu_velo.
  KittiTrackingCalibration c = calibration_;
  WriteKittiTrackingCalibration(layout.Calibration(), c);
  std::ifstream in(layout.Calibration());
  std::string text, line;
  while (std::getline(in, line))
    if (line.rfind("Tr_imu_velo", 0) != 0) text += line + "\n";
  in.close();
  std::ofstream(layout.Calibration()) << text;
  ExpectError([&] { LoadSequenceTracks(folder_, options); }, {"calib/0007.txt: no Tr_imu_velo line"});
}

// The fixture's sequence in KITTI stereo 2015's (multiview) layout:
// ROOT/image_2|image_3/000007_<ff>.png, ROOT/calib_cam_to_cam/000007.txt
// (P_rect_02 with camera 2 6 cm right of camera 0, among other entries), the
// detections as per-frame KITTI object files in rectified camera 0. Without
// poses both are a static camera.
TEST_F(SequenceTest, KittiStereoLayoutGivesTheTracksOfSampsLayout) {
  const fs::path root = dir_.parent_path() / "stereo";
  fs::create_directories(root / "calib_cam_to_cam");
  fs::copy(dir_ / "image_2", root / "image_2");
  fs::copy(dir_ / "image_3", root / "image_3");
  const StereoCalibration c = SmallCalibration();
  Eigen::Matrix3d k;
  k << c.camera.fx, 0, c.camera.cx, 0, c.camera.fy, c.camera.cy, 0, 0, 1;
  const Eigen::Vector3d t2(0.06, 0.0, 0.0027);
  auto row = [&](const Eigen::Vector3d& t) {
    Eigen::Matrix<double, 3, 4> p;
    p << k, k * t;
    std::ostringstream s;
    s << std::setprecision(17);
    for (int r = 0; r < 3; ++r)
      for (int q = 0; q < 4; ++q) s << ' ' << p(r, q);
    return s.str();
  };
  std::ofstream(root / "calib_cam_to_cam" / "000007.txt")
      << "calib_time: 09-Jan-2012 13:57:47\ncorner_dist: 9.950000e-02\nS_02: 1.392000e+03 5.120000e+02\n"
      << "P_rect_00:" << row(Eigen::Vector3d::Zero()) << "\nP_rect_01:" << row(Eigen::Vector3d(-0.54, 0, 0))
      << "\nP_rect_02:" << row(t2) << "\nP_rect_03:" << row(t2 - Eigen::Vector3d(c.baseline, 0, 0)) << "\n";
  for (int t = 0; t < kFrames; ++t) {
    std::vector<ObjectLabel> moved;
    for (const ObjectLabel& label : ReadLabels((dir_ / "detections" / (Tag(t) + ".txt")).string()))
      moved.push_back(MoveLabel(label, -t2));
    WriteLabels((root / "detections" / (Tag(t) + ".txt")).string(), moved);
  }
  fs::remove_all(dir_ / "disparity");
  fs::remove_all(dir_ / "planes");
  fs::remove_all(dir_ / "poses");
  SequenceOptions options;
  options.stereo.num_disparities = 32;
  SequenceSummary samp_summary, stereo_summary;
  const std::vector<Track> samp = LoadSequenceTracks(dir_.string(), options, &samp_summary);
  const std::vector<std::string> sequences = KittiStereoSequences(root.string(), "7");
  ASSERT_EQ(sequences.size(), 1u);
  EXPECT_EQ(KittiStereoSequences(root.string(), "all"), sequences);
  ExpectError([&] { LoadSequenceTracks(sequences[0], options); }, {"KITTI stereo sequence", "has no detections"});
  options.detections_path = (root / "detections").string();
  const std::vector<Track> stereo = LoadSequenceTracks(sequences[0], options, &stereo_summary);
  EXPECT_EQ(stereo_summary.layout, "kitti-stereo");
  EXPECT_EQ(stereo_summary.name, "000007");
  EXPECT_FALSE(stereo_summary.poses_from_file);
  EXPECT_LT((stereo_summary.label_frame_offset + t2).norm(), 1e-12);
  ASSERT_EQ(stereo.size(), 1u);
  ASSERT_EQ(stereo[0].frames.size(), samp[0].frames.size());
  for (size_t i = 0; i < samp[0].frames.size(); ++i) {
    const TrackFrame &a = samp[0].frames[i], &b = stereo[0].frames[i];
    EXPECT_LT((a.detection.position - b.detection.position).norm(), 2e-4);  // 4 decimals, moved twice
    ASSERT_EQ(a.candidate_points_in_world.size(), b.candidate_points_in_world.size());
    for (size_t q = 0; q < a.candidate_points_in_world.size(); ++q)
      ASSERT_LT((a.candidate_points_in_world[q] - b.candidate_points_in_world[q]).norm(), 1e-9);
  }
  ExpectError([&] { KittiStereoSequences(root.string(), "000008"); }, {"has no sequence 000008"});
}

TEST(RealKittiTest, ReadsFrame10) {
  const std::string dir = SharedKitti();
  if (!fs::exists(dir)) GTEST_SKIP() << dir << " not present";
  const SequenceReader reader(dir, SequenceOptions());
  EXPECT_EQ(reader.files().name, "000046");
  ASSERT_EQ(reader.num_frames(), 1);
  EXPECT_EQ(reader.files().frames[0].frame, 10);
  const StereoCalibration& c = reader.calibration();
  EXPECT_NEAR(c.camera.fx, 721.5377, 1e-9);
  EXPECT_NEAR(c.baseline, 0.5327, 1e-3);
  EXPECT_EQ(c.camera.width, 1242);
  EXPECT_EQ(c.camera.height, 375);
  EXPECT_TRUE(reader.has_poses());
  const SequenceFrame frame = reader.ReadFrame(0);
  EXPECT_FALSE(frame.plane_estimated);
  EXPECT_FALSE(frame.disparity_computed);
  EXPECT_NEAR(frame.plane_in_camera[3], 1.66, 0.05);  // ~1.65 m below the camera
  EXPECT_LT(frame.plane_in_camera[1], -0.99);
  ASSERT_EQ(frame.detections.size(), 1u);  // "car", case-insensitive
  EXPECT_NEAR(frame.detections[0].position.z(), 13.3, 1e-9);
  EXPECT_NEAR(frame.world_from_camera.translation().z(), ReadPoses(dir + "/poses/000046.txt")[10].translation().z(), 1e-12);
}

TEST(RealKittiTest, FindsTheCarsPoints) {
  const std::string dir = SharedKitti();
  if (!fs::exists(dir)) GTEST_SKIP() << dir << " not present";
  // Default options: the sequence has one frame, fewer than the default
  // min_track_length, so its one-frame track is kept (and noted).
  SequenceOptions options;
  ASSERT_GT(options.tracker.min_track_length, 1);
  SequenceSummary summary;
  const std::vector<Track> tracks = LoadSequenceTracks(dir, options, &summary);
  ASSERT_EQ(tracks.size(), 1u) << summary.BriefReport();
  bool noted = false;
  for (const std::string& m : summary.messages) noted = noted || m.find("min_track_length") != std::string::npos;
  EXPECT_TRUE(noted) << summary.BriefReport();
  ASSERT_EQ(tracks[0].frames.size(), 1u);
  const TrackFrame& f = tracks[0].frames[0];
  EXPECT_EQ(f.frame, 10);
  ASSERT_GT(f.candidate_points_in_world.size(), 1000u);
  std::vector<float> depths;
  for (float d : f.candidate_disparities_px) depths.push_back(float(tracks[0].calibration.baseline * tracks[0].calibration.camera.fx / d));
  std::sort(depths.begin(), depths.end());
  const float median = depths[depths.size() / 2];
  EXPECT_GT(median, 12.0f);
  EXPECT_LT(median, 15.0f);
  // Points are above the road and near the detection.
  const Eigen::Vector3d center = f.world_from_camera * DetectionCenter(f.detection);
  for (const Eigen::Vector3d& p : f.candidate_points_in_world) {
    ASSERT_GT(f.ground_plane_in_world.head<3>().dot(p) + f.ground_plane_in_world[3], 0.1);
    // Within 4 m of the detection, or on a ray within 4 m of it and within
    // 4 m + 3 sigma along the ray (ObservationOptions::depth_gate_sigmas).
    const Eigen::Vector3d camera = f.world_from_camera.translation();
    const Eigen::Vector3d u = (p - camera).normalized();
    const double along = (center - camera).dot(u);
    ASSERT_LT(((center - camera) - along * u).norm(), 4.0 + 1e-9);
    ASSERT_LT(std::abs((p - camera).norm() - along), 4.0 + 3.0 * 1.0 + 1e-9);  // sigma_ray < 1 m at ~13 m
  }
  // RANSAC on the real stereo agrees with the plane file.
  const SequenceReader reader(dir, options);
  SequenceFrame frame = reader.ReadFrame(0);
  RoadPlaneSummary plane_summary;
  const std::vector<StereoPoint> points =
      DisparityToPoints(frame.disparity_px, reader.calibration(), 1.0, 2, cv::Rect(0, 125, 1242, 250));
  const Eigen::Vector4d plane = EstimateRoadPlane(points, RoadPlaneOptions(), &plane_summary);
  ASSERT_TRUE(plane_summary.success) << plane_summary.BriefReport();
  EXPECT_NEAR(plane[3], frame.plane_in_camera[3], 0.1);
  EXPECT_GT(plane.head<3>().dot(frame.plane_in_camera.head<3>()), std::cos(2.0 * M_PI / 180));
}

}  // namespace
}  // namespace samp
