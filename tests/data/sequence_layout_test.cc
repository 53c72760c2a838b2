#include "libsamp/data/sequence_layout.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "libsamp/core/error.h"

namespace samp {
namespace {

namespace fs = std::filesystem;

TEST(SequenceLayoutTest, FrameTagHasAtLeastTwoDigits) {
  EXPECT_EQ(SequenceLayout::FrameTag("000046", 0), "000046_00");
  EXPECT_EQ(SequenceLayout::FrameTag("000046", 7), "000046_07");
  EXPECT_EQ(SequenceLayout::FrameTag("000046", 10), "000046_10");
  EXPECT_EQ(SequenceLayout::FrameTag("s", 123), "s_123");
  EXPECT_EQ(SequenceLayout::FrameFileName("s", 3, ".png"), "s_03.png");
}

TEST(SequenceLayoutTest, FrameOfFileNameInvertsFrameFileName) {
  for (int frame : {0, 5, 10, 99, 100, 123456}) {
    const std::string name = SequenceLayout::FrameFileName("000046", frame, ".txt");
    EXPECT_EQ(SequenceLayout::FrameOfFileName("some/folder/" + name, "000046", ".txt"), frame) << name;
  }
  EXPECT_EQ(SequenceLayout::FrameOfFileName("000046_3.png", "000046", ".png"), 3);
  EXPECT_EQ(SequenceLayout::FrameOfFileName("000046_03.png", "000046", ".txt"), -1);
  EXPECT_EQ(SequenceLayout::FrameOfFileName("000047_03.png", "000046", ".png"), -1);
  EXPECT_EQ(SequenceLayout::FrameOfFileName("000046_.png", "000046", ".png"), -1);
  EXPECT_EQ(SequenceLayout::FrameOfFileName("000046_0a.png", "000046", ".png"), -1);
  EXPECT_EQ(SequenceLayout::FrameOfFileName("000046_03.png.bak", "000046", ".png"), -1);
  EXPECT_THROW(SequenceLayout::FrameOfFileName("000046_1234567.png", "000046", ".png"), Error);
}

TEST(SequenceLayoutTest, PathsOfTheDocumentedLayout) {
  const SequenceLayout layout("root/seq", "000046");
  auto path = [](const std::string& p) { return fs::path(p).lexically_normal().generic_string(); };
  EXPECT_EQ(path(layout.Calibration()), "root/seq/calib/000046.txt");
  EXPECT_EQ(path(layout.Poses()), "root/seq/poses/000046.txt");
  EXPECT_EQ(path(layout.LeftImage(4)), "root/seq/image_2/000046_04.png");
  EXPECT_EQ(path(layout.RightImage(4)), "root/seq/image_3/000046_04.png");
  EXPECT_EQ(path(layout.Disparity(12)), "root/seq/disparity/000046_12.png");
  EXPECT_EQ(path(layout.Detections(0)), "root/seq/detections/000046_00.txt");
  EXPECT_EQ(path(layout.Plane(1)), "root/seq/planes/000046_01.txt");
  EXPECT_EQ(path(layout.Folder(SequenceLayout::kDisparityFolder)), "root/seq/disparity");
  EXPECT_EQ(path(layout.GroundTruthFolder()), "root/seq/gt");
  EXPECT_EQ(path(layout.GroundTruthLabels()), "root/seq/gt/label_02/000046.txt");
  EXPECT_EQ(path(layout.GroundTruthDepth(2)), "root/seq/gt/depth/000046_02.png");
  EXPECT_EQ(path(layout.GroundTruthObjectMap(2)), "root/seq/gt/obj_map/000046_02.png");
  EXPECT_EQ(path(layout.GroundTruthMesh(3)), "root/seq/gt/meshes/track_3.ply");
  EXPECT_EQ(path(layout.GroundTruthCars()), "root/seq/gt/cars.json");
}

}  // namespace
}  // namespace samp
