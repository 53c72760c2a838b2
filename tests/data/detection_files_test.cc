#include "libsamp/data/detection_files.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "libsamp/core/error.h"
#include "libsamp/data/kitti_io.h"
#include "tests/testing/expect_error.h"

namespace samp {
namespace {

using test::ExpectError;
namespace fs = std::filesystem;

class DetectionFilesTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("samp_detection_files_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

ObjectLabel Car(int frame, double x) {
  ObjectLabel l;
  l.frame = frame;
  l.type = "Car";
  l.box_2d = Eigen::Vector4d(100.5, 150.25, 300, 250);
  l.height = 1.5, l.width = 1.6, l.length = 3.9;
  l.position = Eigen::Vector3d(x, 1.7, 15.5);
  l.rotation_y = -1.2;
  l.alpha = -1.3;
  l.score = 0.875;
  return l;
}

TEST_F(DetectionFilesTest, Ab3dmotRoundTripAndColumnOrder) {
  ObjectLabel cyclist = Car(3, -2);
  cyclist.type = "Cyclist";
  WriteAb3dmotDetections(Path("0004.txt"), {Car(0, 1.25), Car(0, 5), cyclist});
  // The column order as AB3DMOT writes it: frame,type,x1,y1,x2,y2,score,h,w,l,x,y,z,ry,alpha.
  std::ifstream in(Path("0004.txt"));
  std::string first;
  std::getline(in, first);
  EXPECT_EQ(first, "0,2,100.5000,150.2500,300.0000,250.0000,0.875000,1.500000,1.600000,3.900000,1.250000,"
                   "1.700000,15.500000,-1.200000,-1.300000");
  EXPECT_EQ(SniffDetectionFormat(Path("0004.txt")), DetectionFormat::kAb3dmot);
  const std::vector<ObjectLabel> read = ReadDetectionFile(Path("0004.txt"), DetectionFormat::kAuto);
  ASSERT_EQ(read.size(), 3u);
  EXPECT_EQ(read[0].frame, 0);
  EXPECT_EQ(read[0].track_id, -1);
  EXPECT_EQ(read[0].type, "Car");
  EXPECT_EQ(read[2].type, "Cyclist");
  EXPECT_EQ(read[2].frame, 3);
  EXPECT_DOUBLE_EQ(read[0].score, 0.875);
  EXPECT_DOUBLE_EQ(read[0].length, 3.9);
  EXPECT_DOUBLE_EQ(read[0].alpha, -1.3);
  EXPECT_DOUBLE_EQ(read[0].box_2d[1], 150.25);
  EXPECT_TRUE(read[1].position.isApprox(Eigen::Vector3d(5, 1.7, 15.5)));
  // Spaces after the commas (some writers) are accepted.
  std::ofstream(Path("spaced.txt")) << "7, 2, 10, 20, 30, 40, 0.5, 1.5, 1.6, 4, 1, 1.6, 12, 0.1, 0.02\n";
  ASSERT_EQ(ReadAb3dmotDetections(Path("spaced.txt")).size(), 1u);
}

TEST_F(DetectionFilesTest, BadLinesNameFileAndLine) {
  const std::string good = "0,2,10,20,30,40,0.5,1.5,1.6,4,1,1.6,12,0.1,0.02";
  std::ofstream(Path("fields.txt")) << good << "\n0,2,10,20,30,40,0.5,1.5,1.6,4,1,1.6,12,0.1\n";
  ExpectError([&] { ReadAb3dmotDetections(Path("fields.txt")); }, {"fields.txt:2: 14 fields, expected 15"});
  std::ofstream(Path("class.txt")) << good << "\n\n1,7,10,20,30,40,0.5,1.5,1.6,4,1,1.6,12,0.1,0.02\n";
  ExpectError([&] { ReadAb3dmotDetections(Path("class.txt")); }, {"class.txt:3: unknown class id 7", "2 = Car"});
  std::ofstream(Path("nan.txt")) << "0,2,10,20,30,40,0.5,1.5,1.6,4,nan,1.6,12,0.1,0.02\n";
  ExpectError([&] { ReadAb3dmotDetections(Path("nan.txt")); }, {"nan.txt:1: location 'nan' is not a finite number"});
  std::ofstream(Path("behind.txt")) << "0,2,10,20,30,40,0.5,1.5,1.6,4,1,1.6,-12,0.1,0.02\n";
  ExpectError([&] { ReadAb3dmotDetections(Path("behind.txt")); }, {"behind.txt:1: object at z = -12"});
  std::ofstream(Path("frame.txt")) << "x,2,10,20,30,40,0.5,1.5,1.6,4,1,1.6,12,0.1,0.02\n";
  ExpectError([&] { ReadAb3dmotDetections(Path("frame.txt")); }, {"frame.txt:1: frame 'x' is not an integer"});
  // KITTI tracking lines with 14 fields, a NaN.
  std::ofstream(Path("tracking.txt")) << "0 -1 Car 0 0 0 10 20 30 40 1.5 1.6 4 1 1.6 12\n";
  ExpectError([&] { ReadDetectionFile(Path("tracking.txt"), DetectionFormat::kKittiTracking); },
              {"tracking.txt:1: 16 columns, expected 17 or 18"});
  std::ofstream(Path("garbage.txt")) << "\n1 2 3\n";
  ExpectError([&] { ReadDetectionFile(Path("garbage.txt"), DetectionFormat::kAuto); },
              {"garbage.txt:2: 3 columns: not a detection file"});
  // A per-frame KITTI object file is not a sequence's file.
  WriteLabels(Path("object.txt"), {Car(-1, 1)});
  EXPECT_EQ(SniffDetectionFormat(Path("object.txt")), DetectionFormat::kKittiObject);
  ExpectError([&] { ReadDetectionFile(Path("object.txt"), DetectionFormat::kAuto); }, {"no frame column"});
  ExpectError([&] { ParseDetectionFormat("csv"); }, {"'csv' is not one of auto, kitti-object"});
}

TEST_F(DetectionFilesTest, KittiTrackingResultsIgnoreTheIds) {
  ObjectLabel a = Car(2, 1), b = Car(5, 3);
  a.track_id = 7;
  b.track_id = 9;
  WriteTrackingLabels(Path("0011.txt"), {a, b});
  EXPECT_EQ(SniffDetectionFormat(Path("0011.txt")), DetectionFormat::kKittiTracking);
  const std::vector<ObjectLabel> read = ReadDetectionFile(Path("0011.txt"), DetectionFormat::kAuto);
  ASSERT_EQ(read.size(), 2u);
  EXPECT_EQ(read[0].track_id, -1);
  EXPECT_EQ(read[1].frame, 5);
  std::ofstream(Path("empty.txt")) << "\n";
  EXPECT_TRUE(ReadDetectionFile(Path("empty.txt"), DetectionFormat::kAuto).empty());
  // The wrong explicit format: an error naming the line, not a silent misread.
  ExpectError([&] { ReadDetectionFile(Path("0011.txt"), DetectionFormat::kAb3dmot); }, {"0011.txt:1: 1 fields"});
}

}  // namespace
}  // namespace samp
