#include "libsamp/sdf/sdf.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "libsamp/core/error.h"
#include "libsamp/core/wheels.h"
#include "libsamp/scan/scanner.h"
#include "tests/sdf/crack_corpus.h"

namespace samp {
namespace {

#define TEST_NAME ::testing::UnitTest::GetInstance()->current_test_info()->name()

using AnalyticSdf = std::function<double(const Eigen::Vector3d&)>;

ScanOptions TestScanOptions() {
  ScanOptions options;
  options.num_views = 100;
  options.width = 300;
  options.height = 300;
  return options;
}

double BoxSdf(const Eigen::Vector3d& p, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  const Eigen::Vector3d center = 0.5 * (lo + hi), half = 0.5 * (hi - lo);
  const Eigen::Vector3d q = (p - center).cwiseAbs() - half;
  const double outside = q.cwiseMax(0.0).norm();
  const double inside = std::min(q.maxCoeff(), 0.0);
  return outside + inside;
}

struct Comparison {
  double max_error_near = 0.0;   // over voxels with |truth| < 3 voxels
  double max_error_far = 0.0;    // over the other voxels
  int64_t wrong_sign = 0;        // voxels with |truth| > half a voxel and the wrong sign
  int64_t near_voxels = 0;
};

Comparison Compare(const Sdf& sdf, const AnalyticSdf& truth, const char* label) {
  Comparison c;
  const GridSpec& grid = sdf.grid;
  const double h = grid.voxel_size;
  for (int k = 0; k < grid.dims.z(); ++k) {
    for (int j = 0; j < grid.dims.y(); ++j) {
      for (int i = 0; i < grid.dims.x(); ++i) {
        const double expected = truth(grid.Position(i, j, k));
        const double value = sdf.values[size_t(grid.Index(i, j, k))];
        const double error = std::abs(value - expected);
        if (std::abs(expected) < 3 * h) {
          c.max_error_near = std::max(c.max_error_near, error);
          ++c.near_voxels;
        } else {
          c.max_error_far = std::max(c.max_error_far, error);
        }
        if (std::abs(expected) > 0.5 * h && (value > 0) != (expected > 0)) ++c.wrong_sign;
      }
    }
  }
  std::printf("%s: max error near the surface %.4f m, far %.4f m (voxel %.3f m), %lld wrong signs\n",
              label, c.max_error_near, c.max_error_far, h, static_cast<long long>(c.wrong_sign));
  return c;
}

TEST(Sdf, ClosedBoxMatchesTheAnalyticSdf) {
  const Eigen::Vector3d lo(-0.62, -0.31, -0.43), hi(0.58, 0.33, 0.41);
  const Mesh mesh = MakeBoxMesh(lo, hi);
  const ScanResult scan = ScanMesh(mesh, TestScanOptions());
  const GridSpec grid = GridSpec::FromBox(lo.array() - 0.3, hi.array() + 0.3, 0.05);
  const Sdf sdf = ComputeSdf(mesh, scan, grid, SdfOptions());
  EXPECT_EQ(sdf.summary.num_seen_triangles, 12);
  EXPECT_TRUE(sdf.summary.sign_ok);
  const Comparison c = Compare(sdf, [&](const Eigen::Vector3d& p) { return BoxSdf(p, lo, hi); }, TEST_NAME);
  const double h = grid.voxel_size;
  EXPECT_GT(c.near_voxels, 1000);
  EXPECT_LT(c.max_error_near, 0.5 * h);
  EXPECT_LT(c.max_error_far, 0.5 * h);
  EXPECT_EQ(c.wrong_sign, 0);
  // Inside fraction: voxels strictly inside the box over all voxels (the
  // grid has samples on the faces, within rounding: they count as outside).
  int64_t inside = 0;
  for (int k = 0; k < grid.dims.z(); ++k)
    for (int j = 0; j < grid.dims.y(); ++j)
      for (int i = 0; i < grid.dims.x(); ++i) inside += BoxSdf(grid.Position(i, j, k), lo, hi) < -1e-6;
  EXPECT_NEAR(sdf.summary.inside_fraction, double(inside) / grid.NumVoxels(), 1e-3);
}

TEST(Sdf, SphereMatchesTheAnalyticSdf) {
  const Eigen::Vector3d center(0.1, -0.2, 0.05);
  const double radius = 0.55;
  const Mesh mesh = MakeSphereMesh(center, radius, 64, 128);
  const ScanResult scan = ScanMesh(mesh, TestScanOptions());
  const GridSpec grid = GridSpec::FromBox(center.array() - 0.9, center.array() + 0.9, 0.05);
  const Sdf sdf = ComputeSdf(mesh, scan, grid, SdfOptions());
  EXPECT_TRUE(sdf.summary.sign_ok);
  EXPECT_GT(sdf.summary.num_seen_triangles, int(0.99 * mesh.triangles.size()));
  const Comparison c =
      Compare(sdf, [&](const Eigen::Vector3d& p) { return (p - center).norm() - radius; }, TEST_NAME);
  const double h = grid.voxel_size;
  EXPECT_GT(c.near_voxels, 1000);
  EXPECT_LT(c.max_error_near, 0.5 * h);
  EXPECT_LT(c.max_error_far, 0.5 * h);
  EXPECT_EQ(c.wrong_sign, 0);
}

// Visibility semantics on an open box (the face y = lo.y missing): the inside
// of the box is seen through the opening, so it is outside, and the walls
// (seen from both sides) are zero-thickness sheets. The SDF is the unsigned
// distance to the walls everywhere, the inside fraction is zero and the
// model is rejected (sign_ok false) rather than trained on a wrong sign.
TEST(Sdf, OpenBoxIsOutsideEverywhere) {
  const Eigen::Vector3d lo(-0.5, -0.3, -0.4), hi(0.5, 0.3, 0.4);
  Mesh mesh = MakeBoxMesh(lo, hi);
  mesh.triangles.erase(mesh.triangles.begin() + 4, mesh.triangles.begin() + 6);  // y = lo face
  const ScanResult scan = ScanMesh(mesh, TestScanOptions());
  const GridSpec grid = GridSpec::FromBox(lo.array() - 0.25, hi.array() + 0.25, 0.05);
  const Sdf sdf = ComputeSdf(mesh, scan, grid, SdfOptions());
  EXPECT_EQ(sdf.summary.num_seen_triangles, 10);
  EXPECT_EQ(sdf.summary.inside_fraction, 0.0);
  EXPECT_FALSE(sdf.summary.sign_ok);
  // Unsigned distance to the five walls.
  const Eigen::Vector3d center = 0.5 * (lo + hi), half = 0.5 * (hi - lo);
  const double h = grid.voxel_size;
  double max_error = 0.0;
  int64_t inner_voxels = 0;
  for (int k = 0; k < grid.dims.z(); ++k) {
    for (int j = 0; j < grid.dims.y(); ++j) {
      for (int i = 0; i < grid.dims.x(); ++i) {
        const Eigen::Vector3d p = grid.Position(i, j, k);
        const float value = sdf.values[size_t(grid.Index(i, j, k))];
        ASSERT_GE(value, 0.0f);
        const Eigen::Vector3d q = p - center;
        if ((q.cwiseAbs().array() < half.array() - 1e-9).all()) {
          ++inner_voxels;
          // Distance to the nearest of the 5 walls from inside.
          const double d = std::min({half.x() - std::abs(q.x()), half.z() - std::abs(q.z()),
                                     half.y() - q.y()});
          max_error = std::max(max_error, std::abs(value - d));
        }
      }
    }
  }
  EXPECT_GT(inner_voxels, 1000);
  EXPECT_LT(max_error, 0.5 * h);
}

// A box that is closed to the eye but not watertight: six separate quads
// (no shared vertices), each overhanging its neighbours, plus a duplicated
// face. The sign must be that of the solid box.
TEST(Sdf, NonWatertightSoupBoxHasTheSolidSign) {
  const Eigen::Vector3d lo(-0.5, -0.3, -0.4), hi(0.5, 0.3, 0.4);
  const double overhang = 0.02;
  Mesh mesh;
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = 0; side < 2; ++side) {
      Eigen::Vector3d face_lo = lo.array() - overhang, face_hi = hi.array() + overhang;
      face_lo[axis] = face_hi[axis] = side ? hi[axis] : lo[axis];
      face_hi[axis] += 1e-4;  // MakeBoxMesh needs a non-degenerate box: take one of its faces
      Mesh slab = MakeBoxMesh(face_lo, face_hi);
      Mesh quad;
      quad.vertices = slab.vertices;
      // Faces 2*axis (the low side of the thin slab) of MakeBoxMesh's ordering.
      quad.triangles = {slab.triangles[size_t(4 * axis)], slab.triangles[size_t(4 * axis + 1)]};
      mesh.Append(quad);
    }
  }
  mesh.Append(MakeBoxMesh(lo, hi));  // duplicated, coincident faces
  const ScanResult scan = ScanMesh(mesh, TestScanOptions());
  const GridSpec grid = GridSpec::FromBox(lo.array() - 0.25, hi.array() + 0.25, 0.05);
  const Sdf sdf = ComputeSdf(mesh, scan, grid, SdfOptions());
  EXPECT_TRUE(sdf.summary.sign_ok);
  const double h = grid.voxel_size;
  // Near the overhanging edges the surface differs from the box by <= 2 cm.
  const Comparison c = Compare(sdf, [&](const Eigen::Vector3d& p) { return BoxSdf(p, lo, hi); }, TEST_NAME);
  EXPECT_EQ(c.wrong_sign, 0);
  EXPECT_LT(c.max_error_near, 0.5 * h + overhang * std::sqrt(2.0));
}

// A closed hull with geometry inside it (a smaller box and a plane through
// the middle, never seen by the scans): it must not create zero crossings.
TEST(Sdf, InteriorFacesOfAClosedHullAreIgnored) {
  const Eigen::Vector3d lo(-0.6, -0.35, -0.4), hi(0.6, 0.35, 0.4);
  Mesh mesh = MakeBoxMesh(lo, hi);
  mesh.Append(MakeBoxMesh(Eigen::Vector3d(-0.3, -0.1, -0.2), Eigen::Vector3d(0.1, 0.2, 0.15)));
  Mesh plane;
  plane.vertices = {Eigen::Vector3f(-0.55f, 0.0f, -0.35f), Eigen::Vector3f(0.55f, 0.0f, -0.35f),
                    Eigen::Vector3f(0.55f, 0.0f, 0.35f), Eigen::Vector3f(-0.55f, 0.0f, 0.35f)};
  plane.triangles = {Eigen::Vector3i(0, 1, 2), Eigen::Vector3i(0, 2, 3)};
  mesh.Append(plane);
  const ScanResult scan = ScanMesh(mesh, TestScanOptions());
  const GridSpec grid = GridSpec::FromBox(lo.array() - 0.25, hi.array() + 0.25, 0.05);
  const Sdf sdf = ComputeSdf(mesh, scan, grid, SdfOptions());
  EXPECT_EQ(sdf.summary.num_seen_triangles, 12);
  const Comparison c = Compare(sdf, [&](const Eigen::Vector3d& p) { return BoxSdf(p, lo, hi); }, TEST_NAME);
  const double h = grid.voxel_size;
  EXPECT_EQ(c.wrong_sign, 0);
  EXPECT_LT(c.max_error_near, 0.5 * h);
  EXPECT_LT(c.max_error_far, 0.5 * h);
  // Every voxel strictly inside the hull is negative (no spurious crossings).
  for (int k = 0; k < grid.dims.z(); ++k)
    for (int j = 0; j < grid.dims.y(); ++j)
      for (int i = 0; i < grid.dims.x(); ++i)
        if (BoxSdf(grid.Position(i, j, k), lo, hi) < -1e-9)
          ASSERT_LT(sdf.values[size_t(grid.Index(i, j, k))], 0.0f) << i << " " << j << " " << k;
}

// One view only: what it sees in front of the box and around it is outside,
// the box's shadow behind it is inside, voxels outside its frustum are outside.
TEST(Sdf, SingleViewCarvesItsFrontAndLeavesTheShadow) {
  const Eigen::Vector3d lo(-0.3, -0.3, -0.3), hi(0.3, 0.3, 0.3);
  const Mesh mesh = MakeBoxMesh(lo, hi);
  ScanOptions scan_options = TestScanOptions();
  scan_options.num_views = 1;
  scan_options.fov_deg = 20.0;  // narrow: the grid corners are outside the frustum
  const ScanResult scan = ScanMesh(mesh, scan_options);
  const GridSpec grid = GridSpec::FromBox(Eigen::Vector3d::Constant(-1.0), Eigen::Vector3d::Constant(1.0), 0.05);
  const Sdf sdf = ComputeSdf(mesh, scan, grid, SdfOptions());
  const ScanView& view = scan.views[0];
  const Eigen::Vector3d camera_center = view.camera_from_object.inverse().translation();
  const Eigen::Vector3d direction = -camera_center.normalized();  // viewing direction
  int64_t shadow = 0, front = 0, out_of_view = 0;
  for (int k = 0; k < grid.dims.z(); ++k) {
    for (int j = 0; j < grid.dims.y(); ++j) {
      for (int i = 0; i < grid.dims.x(); ++i) {
        const Eigen::Vector3d p = grid.Position(i, j, k);
        const float value = sdf.values[size_t(grid.Index(i, j, k))];
        const Eigen::Vector3d pc = view.camera_from_object * p;
        const bool in_view = pc.z() > 0 && view.camera.Contains(view.camera.Project(pc) +
                                                                Eigen::Vector2d(0.5, 0.5));
        if (!in_view) {
          ++out_of_view;
          ASSERT_GT(value, 0.0f);
          continue;
        }
        // Behind the box along the viewing direction, well inside its shadow.
        const Eigen::Vector3d q = p - direction * (p.dot(direction));  // lateral offset
        const bool deep_shadow = BoxSdf(p, lo, hi) < -0.06 ||
                                 (p.dot(direction) > 0.45 && (q.cwiseAbs().array() < 0.1).all());
        if (deep_shadow) {
          ++shadow;
          ASSERT_LT(value, 0.0f) << p.transpose();
        }
        if (p.dot(direction) < -0.6) {
          ++front;
          ASSERT_GT(value, 0.0f) << p.transpose();
        }
      }
    }
  }
  EXPECT_GT(shadow, 100);
  EXPECT_GT(front, 100);
  EXPECT_GT(out_of_view, 100);
}

TEST(Sdf, ParallelEqualsSerialAndTruncationClamps) {
  const Mesh mesh = MakeSphereMesh(Eigen::Vector3d::Zero(), 0.4, 24, 48);
  const ScanResult scan = ScanMesh(mesh, TestScanOptions());
  const GridSpec grid = GridSpec::FromBox(Eigen::Vector3d::Constant(-0.7), Eigen::Vector3d::Constant(0.7), 0.05);
  const Sdf serial = ComputeSdf(mesh, scan, grid, SdfOptions(), false);
  const Sdf parallel = ComputeSdf(mesh, scan, grid, SdfOptions(), true);
  ASSERT_EQ(serial.values.size(), parallel.values.size());
  for (size_t v = 0; v < serial.values.size(); ++v) ASSERT_EQ(serial.values[v], parallel.values[v]);
  EXPECT_EQ(serial.summary.inside_fraction, parallel.summary.inside_fraction);

  SdfOptions options;
  options.truncation = 0.1;
  const Sdf truncated = ComputeSdf(mesh, scan, grid, options);
  for (size_t v = 0; v < serial.values.size(); ++v) {
    ASSERT_EQ(truncated.values[v], std::clamp(serial.values[v], -0.1f, 0.1f));
  }
}

// The carving rule of docs/sdf.md applied to every voxel and every view,
// without any grouping: true = outside. `distance` = |value| of ComputeSdf.
std::vector<uint8_t> ReferenceCarving(const Mesh& mesh, const ScanResult& scan, const GridSpec& grid,
                                      const std::vector<float>& distance, float margin) {
  const float h = float(grid.voxel_size);
  const Eigen::Vector3f origin = grid.origin.cast<float>();
  const size_t n = size_t(grid.NumVoxels());
  std::vector<uint8_t> carved(n, 0), in_frustum(n, 0);
  constexpr float kInfinity = std::numeric_limits<float>::infinity();
  for (const ScanView& view : scan.views) {
    const Eigen::Matrix3f rotation = view.camera_from_object.linear().cast<float>();
    const Eigen::Vector3f translation = view.camera_from_object.translation().cast<float>();
    const Eigen::Vector3f camera_center = view.camera_from_object.inverse().translation().cast<float>();
    const PinholeCamera& camera = view.camera;
    const float fx = float(camera.fx), fy = float(camera.fy), cx = float(camera.cx), cy = float(camera.cy);
    const float lateral_per_depth =
        float(0.55 * std::sqrt(1.0 / (camera.fx * camera.fx) + 1.0 / (camera.fy * camera.fy)));
    const int coarse_width = (camera.width - 2) / 4 + 1, coarse_height = (camera.height - 2) / 4 + 1;
    const float u_max = float(camera.width) - 0.5f, w_max = float(camera.height) - 0.5f;
    for (int k = 0; k < grid.dims.z(); ++k) {
      for (int j = 0; j < grid.dims.y(); ++j) {
        for (int i = 0; i < grid.dims.x(); ++i) {
          const size_t v = size_t(grid.Index(i, j, k));
          if (carved[v]) continue;
          const Eigen::Vector3f position(origin.x() + h * float(i), origin.y() + h * float(j),
                                         origin.z() + h * float(k));
          const Eigen::Vector3f pc = rotation * position + translation;
          const float z = std::max(pc.z(), 1e-6f);
          const float u = fx * pc.x() * (1.0f / z) + cx, w = fy * pc.y() * (1.0f / z) + cy;
          const bool in_image = pc.z() > 1e-6f && u >= -0.5f && w >= -0.5f && u < u_max && w < w_max;
          in_frustum[v] |= uint8_t(in_image);
          if (!in_image) continue;
          const float uc = std::clamp(u, 0.0f, u_max - 0.5f), wc = std::clamp(w, 0.0f, w_max - 0.5f);
          const int pixel = int(wc + 0.5f) * camera.width + int(uc + 0.5f);
          const float lateral = lateral_per_depth * z;
          // Far voxels: the nearest coarse sample (every 4th pixel from 1) or pixel.
          const float cu = (uc - 1.0f) * 0.25f + 0.5f, cw = (wc - 1.0f) * 0.25f + 0.5f;
          const bool coarse = distance[v] > 4 * lateral && cu < float(coarse_width) && cw < float(coarse_height);
          const float observed =
              coarse ? view.depth[size_t((1 + 4 * int(cw)) * camera.width + 1 + 4 * int(cu))] : view.depth[size_t(pixel)];
          if (distance[v] > lateral) {
            carved[v] = observed == kInfinity || z < observed - margin;
            continue;
          }
          // Near voxels: the plane of the triangle the pixel saw.
          if (!(observed < kInfinity && z < observed + h)) continue;
          const int32_t t = view.triangle[size_t(pixel)];
          if (t < 0 || !scan.triangle_seen[size_t(t)]) continue;
          const Eigen::Vector3i& f = mesh.triangles[size_t(t)];
          const Eigen::Vector3f a = mesh.vertices[size_t(f[0])], b = mesh.vertices[size_t(f[1])],
                                c = mesh.vertices[size_t(f[2])];
          const Eigen::Vector3d nd = (b - a).cast<double>().cross((c - a).cast<double>());
          const Eigen::Vector3f normal =
              nd.norm() > 0 ? Eigen::Vector3f((nd / nd.norm()).cast<float>()) : Eigen::Vector3f::Zero();
          const float offset = normal.dot(a);
          const float side_camera = normal.dot(camera_center) - offset;
          const float side_voxel = normal.dot(position) - offset;
          const float on_plane = 1e-5f * h;
          carved[v] = side_camera > 0.0f   ? side_voxel > margin - on_plane
                      : side_camera < 0.0f ? side_voxel < on_plane - margin
                                           : false;
        }
      }
    }
  }
  std::vector<uint8_t> outside(n);
  for (size_t v = 0; v < n; ++v) outside[v] = carved[v] || !in_frustum[v];
  return outside;
}

// ComputeSdf decides whole blocks and cells of voxels per view where it can
// (docs/sdf.md); the signs must be exactly those of the per-voxel rule.
TEST(Sdf, GroupedCarvingEqualsThePerVoxelRule) {
  struct Case {
    const char* name;
    Mesh mesh;
    ScanOptions scan;
    float margin;
  };
  std::vector<Case> cases;
  Mesh ellipsoid = MakeSphereMesh(Eigen::Vector3d::Zero(), 1.0, 40, 80);
  for (auto& v : ellipsoid.vertices) v = v.cwiseProduct(Eigen::Vector3f(0.9f, 0.35f, 0.45f));
  cases.push_back({"ellipsoid", ellipsoid, TestScanOptions(), 0.0f});
  ScanOptions odd = TestScanOptions();
  odd.num_views = 37;
  odd.width = 233;
  odd.height = 157;
  cases.push_back({"ellipsoid, 37 odd-sized views, margin", ellipsoid, odd, 0.02f});
  Mesh open = MakeBoxMesh(Eigen::Vector3d(-0.6, -0.3, -0.4), Eigen::Vector3d(0.6, 0.3, 0.4));
  open.triangles.erase(open.triangles.begin() + 4, open.triangles.begin() + 6);
  open.Append(MakeBoxMesh(Eigen::Vector3d(-0.2, -0.1, -0.1), Eigen::Vector3d(0.2, 0.1, 0.1)));
  cases.push_back({"open box with a box inside", open, TestScanOptions(), 0.0f});
  ScanOptions one = TestScanOptions();
  one.num_views = 3;
  cases.push_back({"ellipsoid, 3 views", ellipsoid, one, 0.0f});
  for (const Case& c : cases) {
    const ScanResult scan = ScanMesh(c.mesh, c.scan);
    const GridSpec grid = GridSpec::FromBox(Eigen::Vector3d(-1.1, -0.6, -0.7), Eigen::Vector3d(1.1, 0.6, 0.7), 0.04);
    SdfOptions options;
    options.carve_margin = c.margin;
    options.min_inside_fraction = 0.0;
    options.sign = SdfOptions::Sign::kCarving;  // the carving alone is compared here
    const Sdf sdf = ComputeSdf(c.mesh, scan, grid, options);
    std::vector<float> distance(sdf.values.size());
    for (size_t v = 0; v < distance.size(); ++v) distance[v] = std::abs(sdf.values[v]);
    const std::vector<uint8_t> outside = ReferenceCarving(c.mesh, scan, grid, distance, c.margin);
    int64_t differ = 0, inside = 0;
    for (size_t v = 0; v < outside.size(); ++v) {
      differ += std::signbit(sdf.values[v]) == bool(outside[v]);
      inside += !outside[v];
    }
    std::printf("%s: %lld inside, %lld differ\n", c.name, static_cast<long long>(inside),
                static_cast<long long>(differ));
    EXPECT_EQ(differ, 0) << c.name;
    if (std::string(c.name) != "open box with a box inside") EXPECT_GT(inside, 1000) << c.name;
  }
}

// The cracked corpus (docs/sdf.md, "Cracked meshes"): two car-like bodies on
// wheels, each damaged seven ways; the sign of every cracked SDF against the
// clean original's (carving on the clean mesh), on the training grid.
TEST(Sdf, CrackedCorpusKeepsTheCleanSign) {
  const GridSpec grid = GridSpec::CarDefault();
  const ScanOptions scan_options;  // the trainer's defaults
  SdfOptions carving, closing;
  carving.sign = SdfOptions::Sign::kCarving;
  carving.min_inside_fraction = closing.min_inside_fraction = 0.0;
  const std::vector<std::pair<std::string, Mesh>> bodies = {
      {"sedan", AddWheels(test::MakeSedanBody(), WheelOptions()).Combined()},
      {"van", AddWheels(test::MakeVanBody(), WheelOptions()).Combined()}};
  double worst_closing = 0.0, worst_carving = 0.0;
  for (const auto& [name, clean] : bodies) {
    const Sdf reference = ComputeSdf(clean, ScanMesh(clean, scan_options), grid, carving);
    const Sdf clean_closing = ComputeSdf(clean, ScanMesh(clean, scan_options), grid, closing);
    const test::SignDifference own = test::CompareSigns(grid, reference.values, clean_closing.values);
    std::printf("%-6s clean: inside %lld voxels (>= 1 voxel deep), closing differs on %lld (%.2f %%)\n",
                name.c_str(), static_cast<long long>(own.clean_inside), static_cast<long long>(own.wrong),
                100.0 * own.Share());
    EXPECT_GT(own.clean_inside, 2000) << name;
    EXPECT_LE(own.Share(), 0.01) << name;
    for (const test::CrackOptions& variant : test::CrackVariants()) {
      const Mesh cracked = test::CrackMesh(clean, variant);
      const ScanResult scan = ScanMesh(cracked, scan_options);
      const Sdf by_carving = ComputeSdf(cracked, scan, grid, carving);
      const Sdf by_closing = ComputeSdf(cracked, scan, grid, closing);
      const test::SignDifference a = test::CompareSigns(grid, reference.values, by_carving.values);
      const test::SignDifference b = test::CompareSigns(grid, reference.values, by_closing.values);
      std::printf("%-6s %-48s carving %6lld (%6.2f %%)  carving+closing %6lld (%5.2f %%)  "
                  "disagreement %.3f, largest component %.3f\n",
                  name.c_str(), variant.name.c_str(), static_cast<long long>(a.wrong), 100.0 * a.Share(),
                  static_cast<long long>(b.wrong), 100.0 * b.Share(), by_closing.summary.sign_disagreement,
                  by_closing.summary.largest_component_share);
      EXPECT_LE(b.Share(), 0.01) << name << ", " << variant.name;
      worst_closing = std::max(worst_closing, b.Share());
      worst_carving = std::max(worst_carving, a.Share());
    }
  }
  // The corpus bites: the carving alone gets some cracked mesh wrong.
  EXPECT_GT(worst_carving, 0.05);
  std::printf("worst wrong-sign share: carving %.2f %%, carving+closing %.2f %%\n", 100.0 * worst_carving,
              100.0 * worst_closing);
}

TEST(Sdf, QualityGateNamesTheFailingFigure) {
  ScanOptions scan_options = TestScanOptions();
  scan_options.width = scan_options.height = 200;
  const GridSpec grid = GridSpec::FromBox(Eigen::Vector3d(-1.5, -0.8, -0.8), Eigen::Vector3d(1.5, 0.8, 0.8), 0.05);
  SdfOptions options;
  options.min_inside_fraction = 0.0;
  // A closed box fills its box and is one component.
  const Mesh box = MakeBoxMesh(Eigen::Vector3d(-1, -0.5, -0.5), Eigen::Vector3d(1, 0.5, 0.5));
  const Sdf solid = ComputeSdf(box, ScanMesh(box, scan_options), grid, options);
  const SdfQuality good = CheckSdfQuality(solid, box.Bounds(), SdfQualityOptions());
  EXPECT_TRUE(good.pass) << good.reason;
  EXPECT_FALSE(good.borderline) << good.reason;
  EXPECT_GT(good.box_fill, 0.85);  // the voxels on the faces count as outside
  EXPECT_EQ(solid.summary.num_inside_components, 1);
  EXPECT_DOUBLE_EQ(good.largest_component, 1.0);
  EXPECT_GT(good.closing_agreement, 0.99);
  // Two equal boxes apart: the largest component holds half of the inside.
  Mesh two = MakeBoxMesh(Eigen::Vector3d(-1.2, -0.3, -0.3), Eigen::Vector3d(-0.6, 0.3, 0.3));
  two.Append(MakeBoxMesh(Eigen::Vector3d(0.6, -0.3, -0.3), Eigen::Vector3d(1.2, 0.3, 0.3)));
  const Sdf apart = ComputeSdf(two, ScanMesh(two, scan_options), grid, options);
  const SdfQuality split = CheckSdfQuality(apart, two.Bounds(), SdfQualityOptions());
  EXPECT_EQ(apart.summary.num_inside_components, 2);
  EXPECT_NEAR(split.largest_component, 0.5, 0.01);
  EXPECT_FALSE(split.pass);
  EXPECT_NE(split.reason.find("largest inside component share 0.5"), std::string::npos) << split.reason;
  // An open box (one face missing) is empty: its fill is 0.
  Mesh open = box;
  open.triangles.erase(open.triangles.begin() + 4, open.triangles.begin() + 6);
  const Sdf hollow = ComputeSdf(open, ScanMesh(open, scan_options), grid, options);
  const SdfQuality empty = CheckSdfQuality(hollow, open.Bounds(), SdfQualityOptions());
  EXPECT_FALSE(empty.pass);
  EXPECT_NE(empty.reason.find("inside volume / box volume 0.000 below the minimum 0.300"), std::string::npos)
      << empty.reason;
  SdfQualityOptions bad;
  bad.min_box_fill = 0.6;  // above its borderline limit
  EXPECT_THROW(bad.Check(), Error);
}

TEST(Sdf, BadInputIsAnError) {
  const Mesh mesh = MakeBoxMesh(Eigen::Vector3d::Constant(-0.3), Eigen::Vector3d::Constant(0.3));
  ScanOptions scan_options = TestScanOptions();
  scan_options.num_views = 4;
  scan_options.width = scan_options.height = 64;
  const ScanResult scan = ScanMesh(mesh, scan_options);
  const GridSpec grid = GridSpec::FromBox(Eigen::Vector3d::Constant(-0.5), Eigen::Vector3d::Constant(0.5), 0.1);

  ScanResult wrong_size = scan;
  wrong_size.triangle_seen.pop_back();
  EXPECT_THROW(ComputeSdf(mesh, wrong_size, grid, SdfOptions()), Error);

  ScanResult unseen = scan;
  std::fill(unseen.triangle_seen.begin(), unseen.triangle_seen.end(), 0);
  EXPECT_THROW(ComputeSdf(mesh, unseen, grid, SdfOptions()), Error);

  ScanResult short_view = scan;
  short_view.views[0].depth.pop_back();
  EXPECT_THROW(ComputeSdf(mesh, short_view, grid, SdfOptions()), Error);

  SdfOptions options;
  options.min_inside_fraction = 1.5;
  EXPECT_THROW(options.Check(), Error);
  options = SdfOptions();
  options.truncation = -1;
  EXPECT_THROW(ComputeSdf(mesh, scan, grid, options), Error);
  options = SdfOptions();
  options.closing_radius_voxels = 0.0;
  EXPECT_THROW(options.Check(), Error);
}

}  // namespace
}  // namespace samp
