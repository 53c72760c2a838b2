// 2D image boxes (data/image_box.h): the projection of a 3D box, and the
// share of a box inside a union of regions (overlapping regions count once).
#include "libsamp/data/image_box.h"

#include <gtest/gtest.h>

#include <cmath>

namespace samp {
namespace {

TEST(ImageBox, AreaShareInsideTheUnionOfRegions) {
  const Eigen::Vector4d box(10, 20, 30, 40);  // 20 x 20 px
  EXPECT_EQ(AreaShareInside(box, {}), 0.0);
  EXPECT_EQ(AreaShareInside(box, {Eigen::Vector4d(40, 20, 60, 40)}), 0.0);  // beside it
  EXPECT_EQ(AreaShareInside(box, {Eigen::Vector4d(0, 0, 100, 100)}), 1.0);
  EXPECT_DOUBLE_EQ(AreaShareInside(box, {Eigen::Vector4d(0, 0, 20, 100)}), 0.5);
  EXPECT_DOUBLE_EQ(AreaShareInside(box, {Eigen::Vector4d(0, 0, 15, 25)}), 25.0 / 400.0);
  // Two adjacent halves: the whole box; overlapping regions count once.
  EXPECT_DOUBLE_EQ(AreaShareInside(box, {Eigen::Vector4d(0, 0, 20, 100), Eigen::Vector4d(20, 0, 100, 100)}), 1.0);
  EXPECT_DOUBLE_EQ(AreaShareInside(box, {Eigen::Vector4d(0, 0, 20, 100), Eigen::Vector4d(15, 0, 25, 100)}), 0.75);
  EXPECT_DOUBLE_EQ(AreaShareInside(box, {Eigen::Vector4d(0, 0, 20, 30), Eigen::Vector4d(0, 0, 20, 30),
                                         Eigen::Vector4d(0, 25, 15, 100)}),
                   (100.0 + 75.0 - 25.0) / 400.0);
  // A box without area, and an empty (inverted) region.
  EXPECT_EQ(AreaShareInside(Eigen::Vector4d(10, 20, 10, 40), {Eigen::Vector4d(0, 0, 100, 100)}), 0.0);
  EXPECT_EQ(AreaShareInside(box, {Eigen::Vector4d(100, 100, 0, 0)}), 0.0);
}

TEST(ImageBox, ProjectBoxOfACarInFront) {
  const PinholeCamera camera;
  ObjectLabel car;
  car.position = Eigen::Vector3d(0, 1.65, 20);
  car.height = 1.5, car.width = 1.8, car.length = 4.2;
  car.rotation_y = 0.0;  // length along x
  Eigen::Vector4d box;
  ASSERT_TRUE(ProjectBox(car, camera, &box));
  // Symmetric about the principal point in u; from the roof to the bottom in v.
  EXPECT_NEAR(0.5 * (box[0] + box[2]), camera.cx, 1e-9);
  EXPECT_NEAR(box[2] - box[0], camera.fx * 4.2 / (20 - 0.9), 1e-9);
  EXPECT_NEAR(box[3], camera.cy + camera.fy * 1.65 / (20 - 0.9), 1e-9);
  EXPECT_NEAR(box[1], camera.cy + camera.fy * 0.15 / (20 + 0.9), 1e-9);
  // Behind the camera: no box.
  car.position.z() = -10;
  EXPECT_FALSE(ProjectBox(car, camera, &box));
}

}  // namespace
}  // namespace samp
