#include "libsamp/sdf/surface.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "libsamp/core/error.h"

namespace samp {
namespace {

std::vector<float> SphereSdf(const GridSpec& grid, const Eigen::Vector3d& center, double radius) {
  std::vector<float> values(grid.NumVoxels());
  for (int k = 0; k < grid.dims.z(); ++k)
    for (int j = 0; j < grid.dims.y(); ++j)
      for (int i = 0; i < grid.dims.x(); ++i)
        values[grid.Index(i, j, k)] = float((grid.Position(i, j, k) - center).norm() - radius);
  return values;
}

TEST(ExtractSurface, SphereHasRadiusAndOutwardNormals) {
  const GridSpec grid = GridSpec::FromBox(Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(1, 1, 1), 0.05);
  const Eigen::Vector3d center(0.1, -0.05, 0.02);
  const double radius = 0.6;
  const Mesh mesh = ExtractSurface(grid, SphereSdf(grid, center, radius));
  ASSERT_FALSE(mesh.Empty());
  double max_error = 0.0;
  for (const auto& v : mesh.vertices) {
    max_error = std::max(max_error, std::abs((v.cast<double>() - center).norm() - radius));
  }
  EXPECT_LT(max_error, 0.01);
  // Outward: positive volume close to the ball's.
  const double volume = SignedVolume(mesh);
  EXPECT_NEAR(volume, 4.0 / 3.0 * M_PI * radius * radius * radius, 0.01);
  // Every triangle normal points away from the centre.
  const auto normals = mesh.TriangleNormals();
  int inward = 0;
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Eigen::Vector3f c = (mesh.vertices[mesh.triangles[t][0]] + mesh.vertices[mesh.triangles[t][1]] +
                               mesh.vertices[mesh.triangles[t][2]]) / 3.0f;
    if (normals[t].dot(c - center.cast<float>()) < 0) ++inward;
  }
  EXPECT_EQ(inward, 0);
}

TEST(ExtractSurface, EigenOverloadAndIsovalue) {
  const GridSpec grid = GridSpec::FromBox(Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(1, 1, 1), 0.05);
  const std::vector<float> values = SphereSdf(grid, Eigen::Vector3d::Zero(), 0.5);
  const Eigen::VectorXf eigen_values = Eigen::Map<const Eigen::VectorXf>(values.data(), values.size());
  const Mesh mesh = ExtractSurface(grid, eigen_values, 0.2);  // sphere of radius 0.7
  ASSERT_FALSE(mesh.Empty());
  for (const auto& v : mesh.vertices) EXPECT_NEAR(v.norm(), 0.7, 0.01);
}

TEST(ExtractSurface, ShapeCutByTheBorderIsClosed) {
  const GridSpec grid = GridSpec::FromBox(Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(1, 1, 1), 0.1);
  // A sphere that sticks out of the grid at +x.
  const Mesh mesh = ExtractSurface(grid, SphereSdf(grid, Eigen::Vector3d(0.7, 0, 0), 0.6));
  ASSERT_FALSE(mesh.Empty());
  EXPECT_GT(SignedVolume(mesh), 0.3);
  EXPECT_LE(mesh.Bounds().max.x(), 1.0 + grid.voxel_size);
}

TEST(ExtractSurface, EmptyAndBadInput) {
  const GridSpec grid = GridSpec::FromBox(Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(1, 1, 1), 0.1);
  std::vector<float> outside(grid.NumVoxels(), 1.0f);
  EXPECT_TRUE(ExtractSurface(grid, outside).Empty());
  std::vector<float> wrong(10, -1.0f);
  EXPECT_THROW(ExtractSurface(grid, wrong), Error);
  std::vector<float> with_nan(grid.NumVoxels(), 1.0f);
  with_nan[5] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(ExtractSurface(grid, with_nan), Error);
}

}  // namespace
}  // namespace samp
