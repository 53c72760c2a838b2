#include "libsamp/scan/renderer.h"

#include <gtest/gtest.h>

#include "libsamp/core/error.h"

namespace samp {
namespace {

PinholeCamera SmallCamera() {
  PinholeCamera camera;
  camera.width = 160;
  camera.height = 50;
  camera.fx = camera.fy = 93;
  camera.cx = 79.5;
  camera.cy = 24.5;
  return camera;
}

TEST(Render, PlaneAtKnownDepth) {
  // A wall covering the whole view, its front face at z = 5 in the camera.
  const Mesh wall = MakeBoxMesh(Eigen::Vector3d(-20, -20, 0), Eigen::Vector3d(20, 20, 1));
  PlacedMesh placed;
  placed.mesh = &wall;
  placed.camera_from_object.translation() = Eigen::Vector3d(0, 0, 5);
  const PinholeCamera camera = SmallCamera();
  const RenderBuffers buffers = Render(camera, {placed});
  ASSERT_EQ(buffers.width, 160);
  ASSERT_EQ(buffers.height, 50);
  ASSERT_EQ(buffers.depth.size(), size_t(160 * 50));
  for (int v = 0; v < camera.height; ++v) {
    for (int u = 0; u < camera.width; ++u) {
      const size_t i = size_t(v) * camera.width + u;
      ASSERT_NEAR(buffers.Depth(u, v), 5.f, 1e-4) << u << " " << v;
      ASSERT_EQ(buffers.mesh_index[i], 0);
      ASSERT_TRUE(buffers.normal[i].isApprox(Eigen::Vector3f(0, 0, -1), 1e-5));
      // The -z face is triangles 8 and 9 of MakeBoxMesh.
      ASSERT_TRUE(buffers.triangle[i] == 8 || buffers.triangle[i] == 9);
    }
  }
}

TEST(Render, RotatedBoxOccludesAndProjects) {
  // A unit cube turned 45 degrees about the camera's y axis, its centre at z = 10:
  // the edge nearest to the camera is at depth 10 - sqrt(2) * 0.5.
  const Mesh cube = MakeBoxMesh(Eigen::Vector3d(-0.5, -0.5, -0.5), Eigen::Vector3d(0.5, 0.5, 0.5));
  const Mesh wall = MakeBoxMesh(Eigen::Vector3d(-50, -50, 0), Eigen::Vector3d(50, 50, 1));
  PlacedMesh cube_placed{&cube, Eigen::Isometry3d::Identity()};
  cube_placed.camera_from_object.linear() = Eigen::AngleAxisd(M_PI / 4, Eigen::Vector3d::UnitY()).toRotationMatrix();
  cube_placed.camera_from_object.translation() = Eigen::Vector3d(0, 0, 10);
  PlacedMesh wall_placed{&wall, Eigen::Isometry3d::Identity()};
  wall_placed.camera_from_object.translation() = Eigen::Vector3d(0, 0, 20);
  const PinholeCamera camera = SmallCamera();
  const RenderBuffers buffers = Render(camera, {wall_placed, PlacedMesh{nullptr, {}}, cube_placed});

  // The principal point is between pixels; the pixel at (79, 24) looks 0.5 px
  // left/up of the axis, onto a 45-degree face.
  // On that face z = z_edge + |x| with x = z * 0.5 / 93.
  const float expected = float((10 - std::sqrt(2.0) * 0.5) / (1 - 0.5 / 93));
  EXPECT_NEAR(buffers.Depth(79, 24), expected, 2e-3);
  EXPECT_EQ(buffers.mesh_index[24 * 160 + 79], 2);
  // Far corner pixels see the wall.
  EXPECT_NEAR(buffers.Depth(0, 0), 20.f, 1e-3);
  EXPECT_EQ(buffers.mesh_index[0], 0);
  // Silhouette: the cube's side corners (x = +-0.707, z = 10) project 93 * 0.707 / 10 px off centre.
  int cube_pixels_in_row = 0;
  for (int u = 0; u < camera.width; ++u) cube_pixels_in_row += buffers.mesh_index[24 * 160 + u] == 2;
  EXPECT_NEAR(cube_pixels_in_row, 2 * 93 * 0.7071 / 10, 2.0);
  // Depth and normals are consistent with the projection of hit points.
  for (int u = 60; u < 100; ++u) {
    const size_t i = size_t(24) * camera.width + u;
    if (buffers.mesh_index[i] != 2) continue;
    const Eigen::Vector3d point = buffers.depth[i] * camera.Ray(u, 24);
    const Eigen::Vector3d in_object = cube_placed.camera_from_object.inverse() * point;
    EXPECT_NEAR(in_object.cwiseAbs().maxCoeff(), 0.5, 1e-4);
    EXPECT_LT(buffers.normal[i].z(), 0.f);
    EXPECT_NEAR(std::abs(buffers.normal[i].x()), std::sqrt(0.5f), 1e-4);
  }
}

TEST(Render, EmptySceneAndShading) {
  const PinholeCamera camera = SmallCamera();
  const RenderBuffers empty = Render(camera, {});
  for (float d : empty.depth) ASSERT_TRUE(std::isinf(d));
  const std::vector<uint8_t> white = ShadeRender(empty, {});
  ASSERT_EQ(white.size(), size_t(3 * 160 * 50));
  for (uint8_t c : white) ASSERT_EQ(c, 255);

  const Mesh cube = MakeBoxMesh(Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(1, 1, 1));
  PlacedMesh placed{&cube, Eigen::Isometry3d::Identity()};
  placed.camera_from_object.translation() = Eigen::Vector3d(0, 0, 6);
  const RenderBuffers buffers = Render(camera, {placed});
  const std::vector<uint8_t> rgb = ShadeRender(buffers, {Eigen::Vector3f(1.f, 0.f, 0.f)});
  const size_t centre = size_t(24) * 160 + 79;
  EXPECT_EQ(buffers.mesh_index[centre], 0);
  EXPECT_GT(rgb[3 * centre], 100);  // lit red
  EXPECT_EQ(rgb[3 * centre + 1], 0);
  EXPECT_EQ(rgb[3 * centre + 2], 0);
  EXPECT_EQ(rgb[0], 255);  // background corner

  PinholeCamera bad = camera;
  bad.width = 0;
  EXPECT_THROW(Render(bad, {}), Error);
}

}  // namespace
}  // namespace samp
