#include "libsamp/scan/scanner.h"

#include <gtest/gtest.h>

#include <numeric>

#include "libsamp/core/error.h"

namespace samp {
namespace {

ScanOptions SmallScan() {
  ScanOptions options;
  options.num_views = 30;
  options.width = 96;
  options.height = 96;
  return options;
}

TEST(FibonacciSphere, UnitAndBalanced) {
  const std::vector<Eigen::Vector3d> directions = FibonacciSphere(200);
  ASSERT_EQ(directions.size(), 200u);
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& d : directions) {
    EXPECT_NEAR(d.norm(), 1.0, 1e-12);
    sum += d;
  }
  EXPECT_LT(sum.norm() / 200, 0.02);
  // Well spread: no two directions closer than ~half the mean spacing.
  double min_angle = M_PI;
  for (size_t i = 0; i < directions.size(); ++i) {
    for (size_t j = i + 1; j < directions.size(); ++j) {
      min_angle = std::min(min_angle, std::acos(std::min(1.0, directions[i].dot(directions[j]))));
    }
  }
  EXPECT_GT(min_angle, 0.5 * std::sqrt(4 * M_PI / 200));
  EXPECT_EQ(FibonacciSphere(7), FibonacciSphere(7));
  EXPECT_THROW(FibonacciSphere(0), Error);
}

TEST(ScanMesh, SpherePointsLieOnTheRadius) {
  const Eigen::Vector3d center(1, 2, 3);
  const double radius = 0.5;
  const int rings = 64, segments = 128;
  const Mesh sphere = MakeSphereMesh(center, radius, rings, segments);
  const ScanResult result = ScanMesh(sphere, SmallScan());
  ASSERT_EQ(result.views.size(), 30u);
  EXPECT_EQ(result.num_rays, 30 * 96 * 96);
  const PointCloud cloud = result.SurfacePoints();
  EXPECT_EQ(int64_t(cloud.points.size()), result.num_hits);
  // Seen from 3.2 bounding-sphere radii (R = sqrt(3) r for the sphere's box), the
  // sphere's disc has radius tan(asin(r / (3.2 R))) against an image half-width
  // of tan(20 deg): it covers pi/4 * (0.1834 / 0.364)^2 = 0.199 of each image.
  EXPECT_NEAR(double(result.num_hits) / double(result.num_rays), 0.199, 0.01);
  // A facet of the polygonal sphere lies at most r (1 - cos(dtheta)) inside.
  const double max_inset = radius * (1 - std::cos(M_PI / rings)) * 2;
  for (const Eigen::Vector3f& p : cloud.points) {
    const double distance = (p.cast<double>() - center).norm();
    ASSERT_LE(distance, radius + 1e-5);
    ASSERT_GE(distance, radius - max_inset);
  }
  // Every view sees the sphere at its depth: the nearest point is at
  // distance_factor * R - r along the optical axis (bounding-sphere radius R).
  const double big_radius = 0.5 * sphere.Bounds().Size().norm();
  for (const ScanView& view : result.views) {
    const float min_depth = *std::min_element(view.depth.begin(), view.depth.end());
    EXPECT_NEAR(min_depth, 3.2 * big_radius - radius, 2e-3);
    // The optical axis points at the box centre, which is the sphere's centre.
    EXPECT_NEAR((view.camera_from_object * center).head<2>().norm(), 0.0, 1e-9);
  }
}

TEST(ScanMesh, ClosedBoxIsSeenEverywhereAndInteriorNever) {
  Mesh mesh = MakeBoxMesh(Eigen::Vector3d(-2, -0.7, -0.9), Eigen::Vector3d(2, 0.7, 0.9));
  const size_t outer_triangles = mesh.triangles.size();
  mesh.Append(MakeBoxMesh(Eigen::Vector3d(-0.5, -0.3, -0.3), Eigen::Vector3d(0.5, 0.3, 0.3)));
  const ScanResult result = ScanMesh(mesh, SmallScan());
  ASSERT_EQ(result.triangle_seen.size(), mesh.triangles.size());
  for (size_t i = 0; i < mesh.triangles.size(); ++i) {
    EXPECT_EQ(result.triangle_seen[i], i < outer_triangles ? 1 : 0) << "triangle " << i;
  }
  int64_t hits = 0;
  for (const ScanView& view : result.views) {
    ASSERT_EQ(view.depth.size(), size_t(96 * 96));
    for (size_t i = 0; i < view.depth.size(); ++i) {
      ASSERT_EQ(std::isfinite(view.depth[i]), view.triangle[i] >= 0);
      if (view.triangle[i] >= 0) {
        ASSERT_LT(size_t(view.triangle[i]), outer_triangles);
        ++hits;
      }
    }
  }
  EXPECT_EQ(hits, result.num_hits);
  // Every scanned point lies on the outer box's surface.
  for (const Eigen::Vector3f& p : result.SurfacePoints().points) {
    const Eigen::Vector3f q = p.cwiseAbs();
    const float on_face = std::min({std::abs(q.x() - 2.f), std::abs(q.y() - 0.7f), std::abs(q.z() - 0.9f)});
    ASSERT_LT(on_face, 1e-4f) << p.transpose();
    ASSERT_LE(q.x(), 2.f + 1e-4f);
    ASSERT_LE(q.y(), 0.7f + 1e-4f);
    ASSERT_LE(q.z(), 0.9f + 1e-4f);
  }
}

TEST(ScanMesh, OpenBoxSeesTheInsideThroughTheOpening) {
  Mesh mesh = MakeBoxMesh(Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(1, 1, 1));
  mesh.triangles.erase(mesh.triangles.begin() + 10, mesh.triangles.end());  // drop the +z face
  const ScanResult result = ScanMesh(mesh, SmallScan());
  EXPECT_EQ(std::accumulate(result.triangle_seen.begin(), result.triangle_seen.end(), 0), 10);
}

void ExpectSameScan(const ScanResult& a, const ScanResult& b) {
  EXPECT_EQ(a.num_rays, b.num_rays);
  EXPECT_EQ(a.num_hits, b.num_hits);
  EXPECT_EQ(a.triangle_seen, b.triangle_seen);
  ASSERT_EQ(a.views.size(), b.views.size());
  for (size_t v = 0; v < a.views.size(); ++v) {
    EXPECT_TRUE(a.views[v].camera_from_object.matrix() == b.views[v].camera_from_object.matrix());
    EXPECT_EQ(a.views[v].camera.width, b.views[v].camera.width);
    EXPECT_EQ(a.views[v].depth, b.views[v].depth) << "view " << v;
    EXPECT_EQ(a.views[v].triangle, b.views[v].triangle) << "view " << v;
  }
}

// The reusing overload (what training calls per model) overwrites everything:
// after a scan of another mesh with more and larger views it gives the fresh
// scan's result exactly, and it keeps the buffers it reuses.
TEST(ScanMesh, ReusedResultEqualsAFreshScan) {
  const Mesh sphere = MakeSphereMesh(Eigen::Vector3d(0, 0, 0), 0.8, 16, 32);
  const Mesh box = MakeBoxMesh(Eigen::Vector3d(-2, -0.7, -0.9), Eigen::Vector3d(2, 0.7, 0.9));
  ScanOptions big = SmallScan();
  big.num_views = 40;
  big.width = big.height = 120;
  ScanResult reused;
  ScanMesh(sphere, big, &reused);
  ExpectSameScan(reused, ScanMesh(sphere, big));
  const float* first_depth = reused.views[0].depth.data();
  ScanMesh(box, SmallScan(), &reused);
  ExpectSameScan(reused, ScanMesh(box, SmallScan()));
  EXPECT_EQ(reused.views[0].depth.data(), first_depth);  // shrunk in place, not re-allocated
  ScanMesh(sphere, big, &reused);
  ExpectSameScan(reused, ScanMesh(sphere, big));
}

TEST(ScanMesh, OptionsAreChecked) {
  const Mesh box = MakeBoxMesh(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 1, 1));
  ScanOptions options = SmallScan();
  options.num_views = 0;
  EXPECT_THROW(ScanMesh(box, options), Error);
  options = SmallScan();
  options.fov_deg = 180;
  EXPECT_THROW(ScanMesh(box, options), Error);
  options = SmallScan();
  options.distance_factor = 0.5;
  EXPECT_THROW(ScanMesh(box, options), Error);
  EXPECT_THROW(ScanMesh(Mesh(), SmallScan()), Error);
}

}  // namespace
}  // namespace samp
