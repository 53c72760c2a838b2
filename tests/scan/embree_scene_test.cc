#include "libsamp/scan/embree_scene.h"

#include <gtest/gtest.h>

#include <limits>
#include <random>
#include <string>

#include "libsamp/core/error.h"

namespace samp {
namespace {

const Mesh kUnitBox = MakeBoxMesh(Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(1, 1, 1));

TEST(EmbreeScene, HitsABoxAtTheRightDistanceAndMisses) {
  const EmbreeScene scene(kUnitBox);
  EXPECT_TRUE(scene.PacketSize() == 4 || scene.PacketSize() == 8 || scene.PacketSize() == 16);
  std::vector<Eigen::Vector3f> origins = {
      {0, 0, -5},      // through the shared diagonal edge of the -z face (robust traversal)
      {0.3f, 0.2f, 5},  // from +z, towards -z
      {0, 0, -5},      // along x: misses
      {-4, 0.5f, 0.5f},  // from -x
      {0, 0, -5},      // would hit at 4, but t_far is 3.5 for all rays
  };
  std::vector<Eigen::Vector3f> directions = {
      {0, 0, 1}, {0, 0, -1}, {1, 0, 0}, {1, 0, 0}, {0, 0, 1},
  };
  std::vector<RayHit> hits;
  scene.Intersect(origins, directions, &hits);
  ASSERT_EQ(hits.size(), 5u);
  ASSERT_TRUE(hits[0].Hit());
  EXPECT_NEAR(hits[0].t, 4.f, 1e-5);
  EXPECT_EQ(hits[0].geometry, 0);
  EXPECT_TRUE(hits[0].normal.isApprox(Eigen::Vector3f(0, 0, -1), 1e-5)) << hits[0].normal.transpose();
  ASSERT_TRUE(hits[1].Hit());
  EXPECT_NEAR(hits[1].t, 4.f, 1e-5);
  EXPECT_TRUE(hits[1].normal.isApprox(Eigen::Vector3f(0, 0, 1), 1e-5));
  EXPECT_FALSE(hits[2].Hit());
  EXPECT_TRUE(std::isinf(hits[2].t));
  EXPECT_EQ(hits[2].triangle, -1);
  ASSERT_TRUE(hits[3].Hit());
  EXPECT_NEAR(hits[3].t, 3.f, 1e-5);
  EXPECT_TRUE(hits[3].normal.isApprox(Eigen::Vector3f(-1, 0, 0), 1e-5));
  // The -x face is triangles 0 and 1 of MakeBoxMesh.
  EXPECT_TRUE(hits[3].triangle == 0 || hits[3].triangle == 1) << hits[3].triangle;

  scene.Intersect(origins, directions, &hits, 3.5f);
  EXPECT_FALSE(hits[0].Hit());
  EXPECT_FALSE(hits[1].Hit());
  EXPECT_TRUE(hits[3].Hit());

  // Normals face the ray origin also from inside.
  scene.Intersect({Eigen::Vector3f(0, 0, 0)}, {Eigen::Vector3f(0, 1, 0)}, &hits);
  ASSERT_TRUE(hits[0].Hit());
  EXPECT_NEAR(hits[0].t, 1.f, 1e-6);
  EXPECT_TRUE(hits[0].normal.isApprox(Eigen::Vector3f(0, -1, 0), 1e-5));

  EXPECT_THROW(scene.Intersect({Eigen::Vector3f::Zero()}, {}, &hits), Error);
}

TEST(EmbreeScene, GeometryIdsAreMeshIndicesAndNearestWins) {
  const Mesh far_box = MakeBoxMesh(Eigen::Vector3d(-1, -1, 9), Eigen::Vector3d(1, 1, 11));
  const Mesh near_box = MakeBoxMesh(Eigen::Vector3d(-0.5, -0.5, 4), Eigen::Vector3d(0.5, 0.5, 5));
  const Mesh empty;
  const EmbreeScene scene(std::vector<const Mesh*>{&far_box, &empty, &near_box});
  std::vector<RayHit> hits;
  scene.Intersect({Eigen::Vector3f(0, 0, 0), Eigen::Vector3f(0.8f, 0, 0)},
                  {Eigen::Vector3f(0, 0, 1), Eigen::Vector3f(0, 0, 1)}, &hits);
  EXPECT_EQ(hits[0].geometry, 2);
  EXPECT_NEAR(hits[0].t, 4.f, 1e-5);
  EXPECT_EQ(hits[1].geometry, 0);
  EXPECT_NEAR(hits[1].t, 9.f, 1e-5);
}

TEST(EmbreeScene, RejectsBadIndices) {
  Mesh mesh = kUnitBox;
  mesh.triangles.push_back(Eigen::Vector3i(0, 1, 8));
  EXPECT_THROW(EmbreeScene{mesh}, Error);
}

// The geometry created before the check is released (ctest under
// LeakSanitizer, SAMP_SANITIZE=address, reports it otherwise).
TEST(EmbreeScene, RejectsNonFiniteVerticesWithoutLeaking) {
  for (float bad : {std::numeric_limits<float>::infinity(), std::numeric_limits<float>::quiet_NaN()}) {
    Mesh mesh = kUnitBox;
    mesh.vertices[3].y() = bad;
    try {
      EmbreeScene scene({&kUnitBox, &mesh});
      FAIL() << "expected samp::Error";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("non-finite vertex"), std::string::npos) << e.what();
    }
  }
}

TEST(EmbreeScene, OriginAndCameraPathsAgreeWithGeneralRays) {
  const Mesh sphere = MakeSphereMesh(Eigen::Vector3d(0.2, -0.1, 0.3), 1.0, 24, 48);
  const EmbreeScene scene(sphere);
  PinholeCamera camera;
  camera.width = 37;  // not a multiple of any tile size
  camera.height = 23;
  camera.fx = camera.fy = 30;
  camera.cx = 18;
  camera.cy = 11;
  Eigen::Isometry3d world_from_camera = Eigen::Isometry3d::Identity();
  world_from_camera.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  world_from_camera.translation() = world_from_camera.linear() * Eigen::Vector3d(0, 0, -4);
  std::vector<Eigen::Vector3f> origins, directions;
  for (int v = 0; v < camera.height; ++v) {
    for (int u = 0; u < camera.width; ++u) {
      origins.push_back(world_from_camera.translation().cast<float>());
      directions.push_back((world_from_camera.linear() * camera.Ray(u, v).normalized()).cast<float>());
    }
  }
  std::vector<RayHit> general, from_origin;
  scene.Intersect(origins, directions, &general);
  scene.IntersectFromOrigin(origins[0], directions, &from_origin);
  // Camera path over two row bands.
  std::vector<RayHit> top(size_t(10) * camera.width), bottom(size_t(13) * camera.width);
  scene.IntersectCamera(camera, world_from_camera, 0, 10, top.data());
  scene.IntersectCamera(camera, world_from_camera, 10, 23, bottom.data());
  std::vector<RayHit> tiled = top;
  tiled.insert(tiled.end(), bottom.begin(), bottom.end());
  int num_hits = 0;
  for (size_t i = 0; i < general.size(); ++i) {
    num_hits += general[i].Hit();
    for (const std::vector<RayHit>* other : {&from_origin, &tiled}) {
      ASSERT_EQ((*other)[i].Hit(), general[i].Hit()) << i;
      if (!general[i].Hit()) continue;
      EXPECT_NEAR((*other)[i].t, general[i].t, 1e-4);
      EXPECT_EQ((*other)[i].triangle, general[i].triangle);
    }
  }
  EXPECT_GT(num_hits, 100);
  // The image path gives the same hits, depth = z in the camera.
  const size_t n = general.size();
  std::vector<float> depth(n);
  std::vector<int32_t> geometry(n), triangle(n);
  std::vector<Eigen::Vector3f> normal(n);
  EmbreeScene::ImageOutputs outputs;
  outputs.depth = depth.data();
  outputs.geometry = geometry.data();
  outputs.triangle = triangle.data();
  outputs.normal = normal.data();
  scene.IntersectCameraImage(camera, world_from_camera, 0, camera.height, outputs);
  for (size_t i = 0; i < n; ++i) {
    ASSERT_EQ(geometry[i], general[i].geometry) << i;
    ASSERT_EQ(triangle[i], general[i].triangle) << i;
    if (!general[i].Hit()) {
      ASSERT_TRUE(std::isinf(depth[i]));
      continue;
    }
    const Eigen::Vector3f point_in_world = origins[i] + general[i].t * directions[i];
    const Eigen::Vector3d point_in_camera = world_from_camera.inverse() * point_in_world.cast<double>();
    EXPECT_NEAR(depth[i], point_in_camera.z(), 1e-4);
    EXPECT_TRUE(normal[i].isApprox(general[i].normal, 1e-5));
  }
  EXPECT_LT(num_hits, int(general.size()));
  EXPECT_THROW(scene.IntersectCamera(camera, world_from_camera, 0, 24, tiled.data()), Error);
}

// The camera paths cast only the tiles whose pixels can see the scene's
// bounding box. A scene with the same mesh plus a triangle behind the camera
// (a box corner behind the camera plane: every tile is cast) must give the
// same images, also where the box's silhouette lies on pixel centres.
TEST(EmbreeScene, CameraPathsSkipOnlyTilesThatCannotHit) {
  PinholeCamera camera;
  camera.width = 61;  // not a multiple of any tile size
  camera.height = 45;
  camera.fx = camera.fy = 50;
  camera.cx = 30;
  camera.cy = 22;
  const Mesh box = MakeBoxMesh(Eigen::Vector3d(-0.6, -0.4, -0.5), Eigen::Vector3d(0.6, 0.4, 0.5));
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int pose = 0; pose < 12; ++pose) {
    Eigen::Isometry3d world_from_camera = Eigen::Isometry3d::Identity();
    if (pose > 0) {
      world_from_camera.linear() =
          Eigen::AngleAxisd(0.4 * unit(rng), Eigen::Vector3d(unit(rng), unit(rng), unit(rng)).normalized())
              .toRotationMatrix();
    }
    // Pose 0 looks straight at the -z face from 5 m: its edges at x = +-0.6,
    // y = +-0.4 project to u = 30 +- 6, v = 22 +- 4, on pixel centres.
    world_from_camera.translation() =
        world_from_camera.linear() * Eigen::Vector3d(0.5 * unit(rng) * (pose > 0), 0.3 * unit(rng) * (pose > 0),
                                                     -4.5 - 1.5 * (pose == 0 ? 2.0 / 3.0 : std::abs(unit(rng))));
    Mesh behind;
    const Eigen::Vector3d back = world_from_camera * Eigen::Vector3d(0, 0, -1);
    behind.vertices = {back.cast<float>(), (back + Eigen::Vector3d(0.01, 0, 0)).cast<float>(),
                       (back + Eigen::Vector3d(0, 0.01, 0)).cast<float>()};
    behind.triangles = {Eigen::Vector3i(0, 1, 2)};
    const EmbreeScene culled(box);
    const EmbreeScene everything(std::vector<const Mesh*>{&box, &behind});
    const size_t n = size_t(camera.width) * camera.height;
    std::vector<float> depth_culled(n), depth_all(n);
    std::vector<int32_t> geometry_culled(n), geometry_all(n);
    std::vector<Eigen::Vector3f> normal_culled(n), normal_all(n);
    EmbreeScene::ImageOutputs out_culled, out_all;
    out_culled.depth = depth_culled.data();
    out_culled.geometry = geometry_culled.data();
    out_culled.normal = normal_culled.data();
    out_all.depth = depth_all.data();
    out_all.geometry = geometry_all.data();
    out_all.normal = normal_all.data();
    // Rows in two bands, so that the window is met from a band's first row too.
    culled.IntersectCameraImage(camera, world_from_camera, 0, 19, out_culled);
    EmbreeScene::ImageOutputs rest = out_culled;
    rest.depth += 19 * camera.width;
    rest.geometry += 19 * camera.width;
    rest.normal += 19 * camera.width;
    culled.IntersectCameraImage(camera, world_from_camera, 19, camera.height, rest);
    everything.IntersectCameraImage(camera, world_from_camera, 0, camera.height, out_all);
    std::vector<RayHit> hits(n);
    culled.IntersectCamera(camera, world_from_camera, 0, camera.height, hits.data());
    int num_hits = 0;
    for (size_t i = 0; i < n; ++i) {
      ASSERT_EQ(geometry_culled[i], geometry_all[i]) << "pose " << pose << " pixel " << i;
      ASSERT_EQ(hits[i].geometry, geometry_all[i]) << "pose " << pose << " pixel " << i;
      if (geometry_all[i] < 0) {
        ASSERT_TRUE(std::isinf(depth_culled[i]));
        ASSERT_EQ(normal_culled[i], Eigen::Vector3f::Zero());
        continue;
      }
      ++num_hits;
      EXPECT_NEAR(depth_culled[i], depth_all[i], 1e-5);
      // Where a ray meets an edge of the box, which face is reported depends
      // on the order of traversal, which the extra triangle changes.
      const int u = int(i % camera.width), v = int(i / camera.width);
      const Eigen::Vector3d point =
          world_from_camera * (double(depth_all[i]) * camera.Ray(u, v) / camera.Ray(u, v).z());
      const int faces = ((point.cwiseAbs() - Eigen::Vector3d(0.6, 0.4, 0.5)).cwiseAbs().array() < 1e-3).count();
      if (faces < 2) EXPECT_TRUE(normal_culled[i].isApprox(normal_all[i], 1e-5)) << pose << " " << i;
    }
    // The box fills part of the image only: most tiles are skipped.
    EXPECT_GT(num_hits, 40) << "pose " << pose;
    EXPECT_LT(num_hits, int(n) / 3) << "pose " << pose;
  }
  // A box around the camera: every tile is cast.
  const Mesh room = MakeBoxMesh(Eigen::Vector3d(-3, -3, -3), Eigen::Vector3d(3, 3, 3));
  const EmbreeScene inside(room);
  std::vector<RayHit> hits(size_t(camera.width) * camera.height);
  inside.IntersectCamera(camera, Eigen::Isometry3d::Identity(), 0, camera.height, hits.data());
  for (const RayHit& hit : hits) ASSERT_TRUE(hit.Hit());
  // An empty scene: every pixel misses.
  const Mesh empty;
  const EmbreeScene nothing(empty);
  nothing.IntersectCamera(camera, Eigen::Isometry3d::Identity(), 0, camera.height, hits.data());
  for (const RayHit& hit : hits) ASSERT_FALSE(hit.Hit());
}

}  // namespace
}  // namespace samp
