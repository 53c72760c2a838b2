#include "libsamp/data/kitti_io.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "libsamp/core/error.h"
#include "tests/testing/expect_error.h"

namespace samp {
namespace {

using test::ExpectError;

namespace fs = std::filesystem;

class KittiIoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("samp_kitti_io_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string Write(const std::string& name, const std::string& text) {
    const std::string path = (dir_ / name).string();
    std::ofstream(path) << text;
    return path;
  }
  fs::path dir_;
};

const char* kCalib =
    "P0: 721.5377 0 609.5593 0 0 721.5377 172.854 0 0 0 1 0\n"
    "P2: 721.537700 0.000000 609.559300 0.000000 0.000000 721.537700 172.854000 0.000000 "
    "0.000000 0.000000 1.000000 0.000000\n"
    "P3: 721.537700 0.000000 609.559300 -384.381480 0.000000 721.537700 172.854000 1.983557 "
    "0.000000 0.000000 1.000000 -0.000016";  // no final newline, as the real file

TEST_F(KittiIoTest, CalibrationGood) {
  const StereoCalibration c = ReadCalibration(Write("c.txt", kCalib), 1000, 300);
  EXPECT_DOUBLE_EQ(c.camera.fx, 721.5377);
  EXPECT_DOUBLE_EQ(c.camera.fy, 721.5377);
  EXPECT_DOUBLE_EQ(c.camera.cx, 609.5593);
  EXPECT_DOUBLE_EQ(c.camera.cy, 172.854);
  EXPECT_EQ(c.camera.width, 1000);
  EXPECT_EQ(c.camera.height, 300);
  EXPECT_NEAR(c.baseline, 384.38148 / 721.5377, 1e-12);
}

TEST_F(KittiIoTest, CalibrationBaselineFromBothMatrices) {
  // A P2 with its own translation (as in KITTI raw): b = (P2[0,3] - P3[0,3]) / fx.
  const std::string text =
      "P2: 700 0 600 44.857 0 700 170 0.2 0 0 1 0.003\nP3: 700 0 600 -339.5 0 700 170 2.2 0 0 1 0.005\n";
  const StereoCalibration c = ReadCalibration(Write("c.txt", text));
  EXPECT_NEAR(c.baseline, (44.857 + 339.5) / 700.0, 1e-12);
}

TEST_F(KittiIoTest, CalibrationErrors) {
  const std::string p2 = "P2: 700 0 600 0 0 700 170 0 0 0 1 0\n";
  ExpectError([&] { ReadCalibration(Write("a.txt", p2)); }, {"a.txt", "no 'P3:'"});
  ExpectError([&] { ReadCalibration(Write("b.txt", "P3: 700 0 600 -300 0 700 170 0 0 0 1 0\n")); },
              {"b.txt", "no 'P2:'"});
  ExpectError([&] { ReadCalibration(Write("c.txt", p2 + "P3: 700 0 600 -300 0 700 170 0 0 0 1\n")); },
              {"c.txt:2:", "11 numbers"});
  ExpectError([&] { ReadCalibration(Write("d.txt", p2 + "P3: 700 0 600 nan 0 700 170 0 0 0 1 0\n")); },
              {"d.txt:2:", "not a finite number"});
  ExpectError([&] { ReadCalibration(Write("e.txt", p2 + "P3: 700 0 600 -3x0 0 700 170 0 0 0 1 0\n")); },
              {"e.txt:2:", "not a number"});
  ExpectError([&] { ReadCalibration(Write("f.txt", p2 + "P3: 700 0 600 300 0 700 170 0 0 0 1 0\n")); },
              {"f.txt", "not positive"});
  ExpectError([&] { ReadCalibration((dir_ / "missing.txt").string()); }, {"cannot open", "missing.txt"});
}

// Values no camera has (issue 16: 1e300 was read and written as 300-digit
// label coordinates) are refused with the file, line and value.
TEST_F(KittiIoTest, CalibrationPlausibility) {
  const std::string p3 = "P3: 700 0 600 -378 0 700 170 0 0 0 1 0\n";
  ExpectError([&] { ReadCalibration(Write("a.txt", "P2: 1e300 0 600 0 0 1e300 170 0 0 0 1 0\n" + p3)); },
              {"a.txt:1:", "P2: entry (0,0) = 1e+300", "not a plausible calibration value"});
  ExpectError([&] { ReadCalibration(Write("b.txt", "P2: 700 0 600 0 0 700 170 0 0 0 1 0\n"
                                                   "P3: 700 0 600 -378 0 700 170 1e300 0 0 1 0\n")); },
              {"b.txt:2:", "P3: entry (1,3)"});
  ExpectError([&] { ReadCalibration(Write("c.txt", "P2: 0.5 0 600 0 0 0.5 170 0 0 0 1 0\n"
                                                   "P3: 0.5 0 600 -0.27 0 0.5 170 0 0 0 1 0\n")); },
              {"c.txt:1:", "fx = 0.5", "not plausible"});
  ExpectError([&] { ReadCalibration(Write("d.txt", "P2: 700 0 600 0 0 2e5 170 0 0 0 1 0\n" + p3)); },
              {"d.txt:1:", "fy = 200000", "not plausible"});
  // 700 px x 20 m: a baseline no stereo rig has.
  ExpectError([&] { ReadCalibration(Write("e.txt", "P2: 700 0 600 0 0 700 170 0 0 0 1 0\n"
                                                   "P3: 700 0 600 -14000 0 700 170 0 0 0 1 0\n")); },
              {"e.txt", "baseline", "= 20 m", "not plausible"});
  // The principal point against the image size, when it is known.
  const std::string good = Write("f.txt", "P2: 700 0 600 0 0 700 170 0 0 0 1 0\n" + p3);
  EXPECT_NO_THROW(ReadCalibration(good, 1242, 375));
  EXPECT_NO_THROW(ReadCalibration(good));  // size not known: not checked
  EXPECT_EQ(ReadCalibration(good).camera.width, 1242);
  ExpectError([&] { ReadCalibration(good, 400, 375); }, {"f.txt:1:", "principal point (600, 170)", "400x375"});
  ExpectError([&] { ReadCalibration(good, 1242, 120); }, {"f.txt:1:", "outside the 1242x120 image"});
  ExpectError([&] { ReadCalibration(good, -5, 375); }, {"image size -5x375"});
  const std::string negative = Write("g.txt", "P2: 700 0 -3 0 0 700 170 0 0 0 1 0\n"
                                              "P3: 700 0 -3 -378 0 700 170 0 0 0 1 0\n");
  ExpectError([&] { ReadCalibration(negative, 1242, 375); }, {"g.txt:1:", "principal point (-3, 170)"});
}

TEST_F(KittiIoTest, PlaneAndPosePlausibility) {
  ExpectError([&] { ReadPlane(Write("a.txt", "# Matrix\nWIDTH 4\nHEIGHT 1\n0 -1 0 1e300\n")); },
              {"a.txt:4:", "offset d = 1e+300", "not a road plane"});
  ExpectError([&] { ReadPlane(Write("b.txt", "# Matrix\nWIDTH 4\nHEIGHT 1\n0 -1 0 -20000\n")); },
              {"b.txt:4:", "offset d = -20000"});
  ExpectError([&] { ReadPlane(Write("c.txt", "# Matrix\nWIDTH 4\nHEIGHT 1\n0 -1e300 0 1.65\n")); },
              {"c.txt:4:", "-1e300", "cannot be scaled to unit length"});
  // A road 5 km below the camera, and a 53 deg tilt (issue 32).
  ExpectError([&] { ReadPlane(Write("h.txt", "# Matrix\nWIDTH 4\nHEIGHT 1\n0 -1 0 5000\n")); },
              {"h.txt:4:", "offset d = 5000", "not a road plane"});
  ExpectError([&] { ReadPlane(Write("i.txt", "# Matrix\nWIDTH 4\nHEIGHT 1\n0 -0.6018 0.7986 1.65\n")); },
              {"i.txt:4:", "tilted 52.99", "more than 30 deg"});
  EXPECT_NEAR(ReadPlane(Write("j.txt", "# Matrix\nWIDTH 4\nHEIGHT 1\n0 -0.9 0.1 1.65\n"))[3], 1.65 / std::hypot(0.9, 0.1),
              1e-12);
  // Scaled coefficients are the same plane: offset 1.65 m after scaling.
  EXPECT_NEAR(ReadPlane(Write("d.txt", "# Matrix\nWIDTH 4\nHEIGHT 1\n0 -1e5 0 1.65e5\n"))[3], 1.65, 1e-12);
  ExpectError([&] { ReadPoses(Write("e.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 1e300 0 1 0 0 0 0 1 0\n")); },
              {"e.txt:2:", "not an ego pose"});
  ExpectError([&] { ReadPoses(Write("f.txt", "1 0 0 0 0 1 0 -2e6 0 0 1 0\n")); },
              {"f.txt:1:", "|t| = 2e+06 m", "not an ego pose"});
  EXPECT_EQ(ReadPoses(Write("g.txt", "1 0 0 9e5 0 1 0 0 0 0 1 0\n")).size(), 1u);
}

const char* kDetection = "car -1 -1 -0.26 603.13 176.77 847.43 264.91 1.53 1.63 3.88 1.80 1.66 13.30 -0.13 0.999\n";

// Numbers that parse but describe no car (issue 32): refused with file and
// line; a subnormal number is a finite number.
TEST_F(KittiIoTest, LabelPlausibility) {
  const std::string head = "Car 0 0 0.1 ";
  ExpectError([&] { ReadLabels(Write("r.txt", head + "600 170 -1e6 260 1.5 1.6 3.9 1.8 1.6 13 0.1\n")); },
              {"r.txt:1:", "2D box"});
  ExpectError([&] { ReadLabels(Write("s.txt", head + "600 170 800 260 1.5 1.6 3.9 1.8 1.6 13 1e300\n")); },
              {"s.txt:1:", "rotation_y 1e+300"});
  ExpectError([&] { ReadLabels(Write("t.txt", head + "600 170 800 260 1.5 1.6 3.9 1.8 50500 13 0.1\n")); },
              {"t.txt:1:", "more than 10000 m"});
  ExpectError([&] { ReadLabels(Write("u.txt", head + "600 170 800 260 1.5 1.6 390 1.8 1.6 13 0.1\n")); },
              {"u.txt:1:", "more than 50 m"});
  const std::vector<ObjectLabel> tiny =
      ReadLabels(Write("v.txt", head + "600 170 800 260 1.5 1.6 3.9 -4e-320 1.6 13 0.1\n"));
  ASSERT_EQ(tiny.size(), 1u);
  EXPECT_EQ(tiny[0].position.x(), -4e-320);
  ExpectError([&] { ReadLabels(Write("w.txt", head + "600 170 800 260 1.5 1.6 3.9 1e400 1.6 13 0.1\n")); },
              {"w.txt:1:", "not a finite number"});
}

// PNG headers are read by samp before OpenCV decodes anything: the memory
// budget is checked against the announced size (a 1.7 MB PNG announcing
// 30000 x 30000 once took 1.8 GB), and every error names the file.
TEST_F(KittiIoTest, PngHeaderAndMemoryBudget) {
  const std::string disparity = (dir_ / "d.png").string();
  cv::imwrite(disparity, cv::Mat(10, 20, CV_16UC1, cv::Scalar(300)));
  const PngHeader header = ReadPngHeader(disparity);
  EXPECT_EQ(header.width, 20);
  EXPECT_EQ(header.height, 10);
  EXPECT_EQ(header.channels, 1);
  EXPECT_EQ(header.bit_depth, 16);
  EXPECT_EQ(ReadDisparity(disparity, cv::Size(), 20 * 10 * 2).cols, 20);
  ExpectError([&] { ReadDisparity(disparity, cv::Size(), 20 * 10 * 2 - 1); },
              {"d.png: the disparity map's header announces 20 x 10 pixels", "memory budget of 399 bytes"});
  // A forged header: 30000 x 30000 16-bit pixels in 33 bytes.
  std::string forged("\x89PNG\r\n\x1a\n\0\0\0\x0dIHDR", 16);
  for (uint32_t v : {30000u, 30000u}) {
    for (int shift = 24; shift >= 0; shift -= 8) forged.push_back(char((v >> shift) & 0xff));
  }
  forged += std::string("\x10\0\0\0\0\0\0\0\0", 9);  // depth 16, gray, ..., CRC
  const std::string big = Write("big.png", forged);
  ExpectError([&] { ReadDisparity(big); }, {"big.png: the disparity map's header announces 30000 x 30000", "memory budget"});
  ExpectError([&] { ReadImage(Write("text.png", "not a png"), 0, "left image"); }, {"text.png: not a PNG file"});
  ExpectError([&] { ReadPngHeader(Write("cut.png", forged.substr(0, 20))); }, {"cut.png: PNG file cut"});
  std::string bad_type = forged;
  bad_type[25] = 5;
  ExpectError([&] { ReadPngHeader(Write("type.png", bad_type)); }, {"type.png: PNG header has colour type 5"});
  // A valid small header and a body OpenCV cannot decode.
  std::string small = forged;
  small[18] = small[19] = small[22] = small[23] = 0;
  small[19] = 4;
  small[23] = 4;
  ExpectError([&] { ReadImage(Write("body.png", small + "garbage"), -1, "image"); }, {"body.png: "});
}

// Text files are streamed: a line over 1 MiB is an error naming the line, and
// calibration and plane files over 1 MiB are refused.
TEST_F(KittiIoTest, LongLinesAndHugeSmallFilesAreRefused) {
  ExpectError([&] { ReadLabels(Write("long.txt", std::string(kDetection) + std::string(2 << 20, '1'))); },
              {"long.txt:2: line longer than"});
  std::string many_lines = "# Matrix\n";
  while (many_lines.size() < (size_t(3) << 20)) many_lines += std::string(200, ' ') + "\n";
  ExpectError([&] { ReadPlane(Write("huge_plane.txt", many_lines)); }, {"huge_plane.txt: more than 1048576 bytes"});
  std::string poses;
  for (int i = 0; i < 20000; ++i) poses += "1 0 0 " + std::to_string(i) + " 0 1 0 0 0 0 1 0\n";
  EXPECT_EQ(ReadPoses(Write("poses.txt", poses + "\n\n")).size(), 20000u);
  ExpectError([&] { ReadPoses(Write("gap.txt", poses + "\n" + poses)); }, {"gap.txt:20001: blank line inside"});
}

TEST_F(KittiIoTest, LabelsGood) {
  const std::string text = std::string(kDetection) + "\n" +
                           "Pedestrian 0.00 0 1.5 10 20 30 40 1.8 0.6 0.9 -2 1.5 8 1.4\n" +
                           "DontCare -1 -1 -10 500 150 520 170 -1 -1 -1 -1000 -1000 -1000 -10\n";
  const std::vector<ObjectLabel> labels = ReadLabels(Write("l.txt", text));
  ASSERT_EQ(labels.size(), 3u);
  const ObjectLabel& car = labels[0];
  EXPECT_EQ(car.type, "car");
  EXPECT_EQ(car.frame, -1);
  EXPECT_EQ(car.track_id, -1);
  EXPECT_DOUBLE_EQ(car.truncation, -1);
  EXPECT_EQ(car.occlusion, -1);
  EXPECT_DOUBLE_EQ(car.alpha, -0.26);
  EXPECT_TRUE(car.box_2d.isApprox(Eigen::Vector4d(603.13, 176.77, 847.43, 264.91)));
  EXPECT_DOUBLE_EQ(car.height, 1.53);
  EXPECT_DOUBLE_EQ(car.width, 1.63);
  EXPECT_DOUBLE_EQ(car.length, 3.88);
  EXPECT_TRUE(car.position.isApprox(Eigen::Vector3d(1.80, 1.66, 13.30)));
  EXPECT_DOUBLE_EQ(car.rotation_y, -0.13);
  EXPECT_DOUBLE_EQ(car.score, 0.999);
  EXPECT_DOUBLE_EQ(labels[1].score, 1.0);  // 15 columns: default score
  EXPECT_TRUE(SameObjectType(labels[0].type, "Car"));
  EXPECT_FALSE(SameObjectType(labels[1].type, "Car"));
  EXPECT_TRUE(ReadLabels(Write("empty.txt", "")).empty());
}

TEST_F(KittiIoTest, LabelErrors) {
  ExpectError([&] { ReadLabels(Write("a.txt", std::string(kDetection) + "Car 0 0 0 1 2 3 4 1 1 1 0 0 10\n")); },
              {"a.txt:2:", "14 columns"});
  ExpectError([&] { ReadLabels(Write("b.txt", "Car 0 0 0 1 2 3 4 1 1 1 0 nan 10 0\n")); },
              {"b.txt:1:", "location", "not a finite number"});
  ExpectError([&] { ReadLabels(Write("c.txt", "Car 0 0 0 1 2 3 4 1 1 1 0 1.6 -5 0\n")); },
              {"c.txt:1:", "behind the camera"});
  ExpectError([&] { ReadLabels(Write("d.txt", "Car 0 0 0 1 2 3 4 1 1 1 0 1.6 0 0\n")); },
              {"d.txt:1:", "behind the camera"});
  ExpectError([&] { ReadLabels(Write("e.txt", "Car 0 0 0 5 2 3 4 1 1 1 0 1.6 9 0\n")); },
              {"e.txt:1:", "x2 < x1"});
  ExpectError([&] { ReadLabels(Write("f.txt", "Car 0 0 0 1 2 3 4 1 -1 1 0 1.6 9 0\n")); },
              {"f.txt:1:", "negative object size"});
  ExpectError([&] { ReadLabels(Write("g.txt", "Car 0 0.5 0 1 2 3 4 1 1 1 0 1.6 9 0\n")); },
              {"g.txt:1:", "occlusion"});
  ExpectError([&] { ReadLabels(Write("h.txt", "Car 0 0 0 1 2 3 4 1 1 1 0 1.6 9 0 inf\n")); },
              {"h.txt:1:", "score"});
  ExpectError([&] { ReadLabels((dir_ / "none.txt").string()); }, {"cannot open", "none.txt"});
}

TEST_F(KittiIoTest, TrackingLabels) {
  const std::string text =
      "0 3 Car 0 0 -1.5 100 150 200 220 1.5 1.6 3.9 -3 1.6 12 -1.5 0.9\n"
      "1 -1 DontCare -1 -1 -10 500 150 520 170 -1 -1 -1 -1000 -1000 -1000 -10\n"
      "2 3 Car 0 0 -1.5 100 150 200 220 1.5 1.6 3.9 -2 1.6 12 -1.5\n";
  const std::vector<ObjectLabel> labels = ReadTrackingLabels(Write("t.txt", text));
  ASSERT_EQ(labels.size(), 3u);
  EXPECT_EQ(labels[0].frame, 0);
  EXPECT_EQ(labels[0].track_id, 3);
  EXPECT_DOUBLE_EQ(labels[0].score, 0.9);
  EXPECT_EQ(labels[1].type, "DontCare");
  EXPECT_EQ(labels[2].frame, 2);
  EXPECT_DOUBLE_EQ(labels[2].position.x(), -2);

  ExpectError([&] { ReadTrackingLabels(Write("a.txt", std::string(kDetection))); }, {"a.txt:1:", "16 columns"});
  ExpectError([&] { ReadTrackingLabels(Write("b.txt", "x 3 Car 0 0 0 1 2 3 4 1 1 1 0 1.6 9 0\n")); },
              {"b.txt:1:", "frame"});
  ExpectError([&] { ReadTrackingLabels(Write("c.txt", "0 1.5 Car 0 0 0 1 2 3 4 1 1 1 0 1.6 9 0\n")); },
              {"c.txt:1:", "track_id"});
  ExpectError([&] { ReadTrackingLabels(Write("d.txt", "-1 2 Car 0 0 0 1 2 3 4 1 1 1 0 1.6 9 0\n")); },
              {"d.txt:1:", "negative"});
  ExpectError([&] { ReadTrackingLabels(Write("e.txt", "0 2 Car 0 0 0 1 2 3 4 1 1 1 0 1.6 -9 0\n")); },
              {"e.txt:1:", "behind the camera"});
}

TEST_F(KittiIoTest, LabelsRoundTrip) {
  ObjectLabel a;
  a.frame = 4;
  a.track_id = 7;
  a.type = "Car";
  a.truncation = 0.25;
  a.occlusion = 1;
  a.alpha = -1.2345;
  a.box_2d = Eigen::Vector4d(10.25, 20.5, 300.75, 200);
  a.height = 1.5;
  a.width = 1.6;
  a.length = 3.9;
  a.position = Eigen::Vector3d(-3.25, 1.65, 22.125);
  a.rotation_y = 3.1416;
  a.score = 0.875;
  ObjectLabel b = a;
  b.track_id = 8;
  b.position.z() = 5;
  const std::string tracking = (dir_ / "out" / "label_02" / "0001.txt").string();
  WriteTrackingLabels(tracking, {a, b});
  const std::vector<ObjectLabel> read = ReadTrackingLabels(tracking);
  ASSERT_EQ(read.size(), 2u);
  EXPECT_EQ(read[0].frame, 4);
  EXPECT_EQ(read[0].track_id, 7);
  EXPECT_EQ(read[1].track_id, 8);
  EXPECT_EQ(read[0].occlusion, 1);
  EXPECT_TRUE(read[0].box_2d.isApprox(a.box_2d));
  EXPECT_TRUE(read[0].position.isApprox(a.position));
  EXPECT_DOUBLE_EQ(read[0].alpha, -1.2345);
  EXPECT_DOUBLE_EQ(read[0].rotation_y, 3.1416);
  EXPECT_DOUBLE_EQ(read[0].score, 0.875);
  EXPECT_DOUBLE_EQ(read[1].position.z(), 5);

  const std::string detections = (dir_ / "d.txt").string();
  WriteLabels(detections, {a});
  const std::vector<ObjectLabel> plain = ReadLabels(detections);
  ASSERT_EQ(plain.size(), 1u);
  EXPECT_EQ(plain[0].frame, -1);
  EXPECT_TRUE(plain[0].position.isApprox(a.position));

  ObjectLabel bad = a;
  bad.type = "Big Car";
  EXPECT_THROW(WriteLabels((dir_ / "bad.txt").string(), {bad}), Error);
  bad = a;
  bad.position.x() = std::nan("");
  EXPECT_THROW(WriteTrackingLabels((dir_ / "bad2.txt").string(), {bad}), Error);
  EXPECT_FALSE(fs::exists(dir_ / "bad2.txt"));  // nothing partial written
}

TEST_F(KittiIoTest, Plane) {
  const Eigen::Vector4d p = ReadPlane(
      Write("p.txt", "# Matrix\nWIDTH 4\nHEIGHT 1\n-8.836576e-03 -9.999590e-01 1.953901e-03 1.659318e+00 \n"));
  EXPECT_NEAR(p.head<3>().norm(), 1.0, 1e-12);
  EXPECT_NEAR(p[3], 1.659318 / Eigen::Vector3d(-8.836576e-03, -9.999590e-01, 1.953901e-03).norm(), 1e-9);
  EXPECT_LT(p[1], 0);
  // Scaled and downward normal: normalised and flipped.
  const Eigen::Vector4d q = ReadPlane(Write("q.txt", "# Matrix\nWIDTH 4\nHEIGHT 1\n0 2 0 -3.3\n"));
  EXPECT_TRUE(q.isApprox(Eigen::Vector4d(0, -1, 0, 1.65)));
  // Writer round trip.
  const std::string written = (dir_ / "w.txt").string();
  WritePlane(written, Eigen::Vector4d(0.01, -0.9999, 0.002, 1.7));
  const Eigen::Vector4d written_plane(0.01, -0.9999, 0.002, 1.7);
  EXPECT_TRUE(ReadPlane(written).isApprox(written_plane / written_plane.head<3>().norm(), 1e-6));

  ExpectError([&] { ReadPlane(Write("a.txt", "# Matrix\nWIDTH 4\nHEIGHT 1\n0 -1 0\n")); }, {"a.txt:4:", "3 numbers"});
  ExpectError([&] { ReadPlane(Write("b.txt", "# Matrix\nWIDTH 3\nHEIGHT 1\n0 -1 0 1\n")); }, {"b.txt:2:", "WIDTH 4"});
  ExpectError([&] { ReadPlane(Write("c.txt", "0 -1 0 1.65\n")); }, {"c.txt", "expected 4"});
  ExpectError([&] { ReadPlane(Write("d.txt", "# Matrix\nWIDTH 4\nHEIGHT 1\n0 -1 NaN 1\n")); },
              {"d.txt:4:", "not a finite number"});
  ExpectError([&] { ReadPlane(Write("e.txt", "# Matrix\nWIDTH 4\nHEIGHT 1\n1 0 0 1\n")); }, {"e.txt:4:", "vertical"});
  ExpectError([&] { ReadPlane(Write("f.txt", "# Matrix\nWIDTH 4\nHEIGHT 1\n0 0 0 1\n")); }, {"f.txt:4:", "zero length"});
}

TEST_F(KittiIoTest, Poses) {
  const std::string text =
      "1 0 0 0 0 1 0 0 0 0 1 0\n"
      "1 0.000126277 7.06371e-05 -0.00150083 -0.000126277 1 9.08131e-06 -0.0022333 -7.06359e-05 "
      "-9.09023e-06 1 -0.00184312\n"
      "0 0 1 5 0 1 0 0 -1 0 0 2\n\n";
  const std::vector<Eigen::Isometry3d> poses = ReadPoses(Write("p.txt", text));
  ASSERT_EQ(poses.size(), 3u);
  EXPECT_TRUE(poses[0].isApprox(Eigen::Isometry3d::Identity()));
  EXPECT_NEAR(poses[1].translation().x(), -0.00150083, 1e-12);
  EXPECT_NEAR((poses[1].linear().transpose() * poses[1].linear() - Eigen::Matrix3d::Identity()).norm(), 0, 1e-12);
  // Frame 2: camera z axis -> world x; point (0, 0, 1) in camera -> (6, 0, 2).
  EXPECT_TRUE((poses[2] * Eigen::Vector3d(0, 0, 1)).isApprox(Eigen::Vector3d(6, 0, 2)));

  const std::string written = (dir_ / "w.txt").string();
  WritePoses(written, poses);
  const std::vector<Eigen::Isometry3d> again = ReadPoses(written);
  ASSERT_EQ(again.size(), 3u);
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(again[i].isApprox(poses[i], 1e-10));

  ExpectError([&] { ReadPoses(Write("a.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1\n")); },
              {"a.txt:2:", "11 numbers"});
  ExpectError([&] { ReadPoses(Write("b.txt", "2 0 0 0 0 1 0 0 0 0 1 0\n")); }, {"b.txt:1:", "not a rotation"});
  ExpectError([&] { ReadPoses(Write("c.txt", "-1 0 0 0 0 1 0 0 0 0 1 0\n")); }, {"c.txt:1:", "not a rotation"});
  ExpectError([&] { ReadPoses(Write("d.txt", "1 0 0 0 0 1 0 0 0 0 1 nan\n")); }, {"d.txt:1:", "not a finite"});
  ExpectError([&] { ReadPoses(Write("e.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n\n1 0 0 0 0 1 0 0 0 0 1 0\n")); },
              {"e.txt:2:", "blank line"});
  ExpectError([&] { ReadPoses(Write("f.txt", "")); }, {"f.txt", "no poses"});
}

TEST_F(KittiIoTest, Disparity) {
  cv::Mat disparity(4, 6, CV_32FC1, cv::Scalar(0));
  disparity.at<float>(1, 2) = 12.5f;
  disparity.at<float>(3, 5) = 0.00390625f;  // 1/256
  disparity.at<float>(2, 2) = -3.0f;        // invalid
  disparity.at<float>(0, 0) = std::nanf("");  // invalid
  const std::string path = (dir_ / "disp" / "d.png").string();
  WriteDisparity(path, disparity);
  const cv::Mat raw = cv::imread(path, cv::IMREAD_UNCHANGED);
  ASSERT_EQ(raw.type(), CV_16UC1);
  EXPECT_EQ(raw.at<uint16_t>(1, 2), 3200);
  const cv::Mat read = ReadDisparity(path, cv::Size(6, 4));
  ASSERT_EQ(read.type(), CV_32FC1);
  EXPECT_FLOAT_EQ(read.at<float>(1, 2), 12.5f);
  EXPECT_FLOAT_EQ(read.at<float>(3, 5), 1.0f / 256);
  EXPECT_FLOAT_EQ(read.at<float>(2, 2), 0.0f);
  EXPECT_FLOAT_EQ(read.at<float>(0, 0), 0.0f);
  EXPECT_EQ(ReadDisparity(path).size(), cv::Size(6, 4));

  ExpectError([&] { ReadDisparity(path, cv::Size(7, 4)); }, {"d.png", "6x4", "expected 7x4"});
  const std::string eight_bit = (dir_ / "eight.png").string();
  cv::imwrite(eight_bit, cv::Mat(4, 6, CV_8UC1, cv::Scalar(5)));
  ExpectError([&] { ReadDisparity(eight_bit); }, {"eight.png", "16-bit", "8-bit"});
  const std::string color = (dir_ / "color.png").string();
  cv::imwrite(color, cv::Mat(4, 6, CV_16UC3, cv::Scalar(5, 5, 5)));
  ExpectError([&] { ReadDisparity(color); }, {"color.png", "3 channel"});
  ExpectError([&] { ReadDisparity(Write("text.png", "not a png")); }, {"text.png", "not a PNG file"});
  ExpectError([&] { ReadDisparity((dir_ / "none.png").string()); }, {"cannot open", "none.png"});
  cv::Mat too_large(2, 2, CV_32FC1, cv::Scalar(300.0f));
  EXPECT_THROW(WriteDisparity((dir_ / "big.png").string(), too_large), Error);
  EXPECT_FALSE(fs::exists(dir_ / "big.png"));
}

TEST_F(KittiIoTest, CalibrationRoundTrip) {
  StereoCalibration c;
  c.baseline = 0.54;
  c.camera.fx = c.camera.fy = 700;
  const std::string path = (dir_ / "calib" / "000001.txt").string();
  WriteCalibration(path, c);
  const StereoCalibration read = ReadCalibration(path, 640, 192);
  EXPECT_NEAR(read.baseline, 0.54, 1e-12);
  EXPECT_DOUBLE_EQ(read.camera.fx, 700);
  EXPECT_DOUBLE_EQ(read.camera.cx, c.camera.cx);
  EXPECT_EQ(read.camera.width, 640);
}

}  // namespace
}  // namespace samp
