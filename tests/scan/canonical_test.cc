#include "libsamp/scan/canonical.h"

#include <gtest/gtest.h>

#include "libsamp/core/error.h"
#include "test_util.h"
#include "tests/testing/expect_error.h"

namespace samp {
namespace {

namespace fs = std::filesystem;

using test::ExpectError;

// A 4.5 x 1.5 x 1.8 m car box in centimetres, z up, front towards -y:
// CAD x = width (180), y = length (450), z = height (150), resting on z = 20.
Mesh CentimetreCarBox() {
  return MakeBoxMesh(Eigen::Vector3d(-90, -225, 20) + Eigen::Vector3d(300, 0, 0),
                     Eigen::Vector3d(90, 225, 170) + Eigen::Vector3d(300, 0, 0));
}

TEST(Canonicalize, CentimetresZUpMinusYForward) {
  CanonicalizeOptions options;
  options.scale = 0.01;
  options.up = "+z";
  options.forward = "-y";
  const CanonicalizeResult result = Canonicalize(CentimetreCarBox(), options);
  EXPECT_TRUE(result.size.isApprox(Eigen::Vector3d(4.5, 1.5, 1.8), 1e-6)) << result.size.transpose();
  const AlignedBox box = result.mesh.Bounds();
  EXPECT_TRUE(box.min.isApprox(Eigen::Vector3d(-2.25, -1.5, -0.9), 1e-5)) << box.min.transpose();
  EXPECT_TRUE(box.max.isApprox(Eigen::Vector3d(2.25, 0, 0.9), 1e-5) && std::abs(box.max.y()) < 1e-5)
      << box.max.transpose();
  EXPECT_EQ(result.up, "+z");
  EXPECT_EQ(result.forward, "-y");
  EXPECT_DOUBLE_EQ(result.scale, 0.01);
  EXPECT_TRUE(result.warnings.empty());
  // The front (CAD -y) maps to +x, the roof (CAD +z) to -y (y points down), and
  // the car's left (CAD +x when looking along -y with z up) to +z.
  const Eigen::Affine3d& t = result.object_from_cad;
  EXPECT_NEAR((t * Eigen::Vector3d(300, -225, 95)).x(), 2.25, 1e-9);
  EXPECT_NEAR((t * Eigen::Vector3d(300, 0, 170)).y(), -1.5, 1e-9);
  EXPECT_NEAR((t * Eigen::Vector3d(300, 0, 20)).y(), 0.0, 1e-9);
  EXPECT_NEAR((t * Eigen::Vector3d(390, 0, 95)).z(), 0.9, 1e-9);
  // Proper rotation (no mirroring).
  EXPECT_NEAR(t.linear().determinant(), std::pow(0.01, 3), 1e-12);
}

TEST(Canonicalize, ApolloCar3DPresetMapsXAcrossYDownFrontPlusZ) {
  // Apollo frame: x across (to the car's right), y down, z to the front; a
  // 1.8 x 1.5 x 4.5 m box centred at 0 .
  Mesh mesh = MakeBoxMesh(Eigen::Vector3d(-0.9, -0.75, -2.25), Eigen::Vector3d(0.9, 0.75, 2.25));
  const CanonicalizeResult result = Canonicalize(mesh, CanonicalPreset("apollocar3d"));
  EXPECT_TRUE(result.size.isApprox(Eigen::Vector3d(4.5, 1.5, 1.8), 1e-6)) << result.size.transpose();
  const Eigen::Affine3d& t = result.object_from_cad;
  EXPECT_NEAR((t * Eigen::Vector3d(0, 0, 2.25)).x(), 2.25, 1e-9);   // front -> +x
  EXPECT_NEAR((t * Eigen::Vector3d(0, 0.75, 0)).y(), 0.0, 1e-9);    // bottom (+y) on the road
  EXPECT_NEAR((t * Eigen::Vector3d(0, -0.75, 0)).y(), -1.5, 1e-9);  // roof up
  EXPECT_NEAR((t * Eigen::Vector3d(-0.9, 0, 0)).z(), 0.9, 1e-9);    // -x (the car's left) -> +z
  EXPECT_NEAR(t.linear().determinant(), 1.0, 1e-12);
  EXPECT_TRUE(result.warnings.empty());
}

TEST(Canonicalize, ShapeNetPresetScalesTheUnitDiagonal) {
  // ShapeNetCore v2: +y up, front -z, unit bounding-box diagonal.
  const Eigen::Vector3d size_lhw(3.9, 1.56, 1.60);
  const Eigen::Vector3d half = 0.5 * size_lhw / size_lhw.norm();  // (length, height, width) halves
  const Mesh mesh = MakeBoxMesh(Eigen::Vector3d(-half.z(), -half.y(), -half.x()),
                                Eigen::Vector3d(half.z(), half.y(), half.x()));
  const CanonicalizeResult result = Canonicalize(mesh, CanonicalPreset("shapenet"));
  EXPECT_NEAR(result.size.x(), 3.9 * 4.49 / size_lhw.norm(), 1e-6);
  EXPECT_NEAR(result.size.y(), 1.56 * 4.49 / size_lhw.norm(), 1e-6);
  EXPECT_NEAR((result.object_from_cad * Eigen::Vector3d(0, 0, -half.x())).x(), 0.5 * result.size.x(), 1e-6);
  EXPECT_NEAR(result.object_from_cad.linear().determinant(), std::pow(4.49, 3), 1e-6);
  EXPECT_THROW(CanonicalPreset("kitti"), Error);
}

TEST(Canonicalize, SynthesisedWheelsTouchTheRoad) {
  CanonicalizeOptions options;
  options.scale = 0.01;
  options.up = "+z";
  options.forward = "-y";
  options.add_wheels = true;
  const CanonicalizeResult result = Canonicalize(CentimetreCarBox(), options);
  ASSERT_TRUE(result.wheels_added);
  const AlignedBox box = result.mesh.Bounds();
  EXPECT_NEAR(box.max.y(), 0.0, 1e-5);  // the tyres
  EXPECT_NEAR(box.min.y(), -1.5 - options.wheels.ground_clearance, 1e-5);
  EXPECT_NEAR(result.size.y(), 1.5 + options.wheels.ground_clearance, 1e-5);
  EXPECT_EQ(result.mesh.triangles.size(), 12u + 4u * 4u * size_t(options.wheels.segments));
  // object_from_cad maps the body's bottom (CAD z = 20) to the lifted body.
  EXPECT_NEAR((result.object_from_cad * Eigen::Vector3d(300, 0, 20)).y(),
              -options.wheels.ground_clearance, 1e-6);
}

TEST(Canonicalize, TargetLengthScalesToMetres) {
  Mesh mesh = CentimetreCarBox();
  mesh.Transform(Eigen::Affine3d(Eigen::Scaling(10.0)));  // millimetres
  CanonicalizeOptions options;
  options.target_length = 4.5;
  options.up = "+z";
  options.forward = "-y";
  const CanonicalizeResult result = Canonicalize(mesh, options);
  EXPECT_NEAR(result.scale, 0.001, 1e-12);
  EXPECT_TRUE(result.size.isApprox(Eigen::Vector3d(4.5, 1.5, 1.8), 1e-6));
}

TEST(Canonicalize, AutoDetectsYUpCarAndWarnsAboutSigns) {
  // y up (glTF style), length along x, width along z.
  const Mesh mesh = MakeBoxMesh(Eigen::Vector3d(-2, 0, -0.9), Eigen::Vector3d(2.5, 1.5, 0.9));
  const CanonicalizeResult result = Canonicalize(mesh, CanonicalizeOptions());
  EXPECT_EQ(result.forward, "+x");
  EXPECT_EQ(result.up, "+y");
  EXPECT_TRUE(result.size.isApprox(Eigen::Vector3d(4.5, 1.5, 1.8), 1e-6));
  EXPECT_EQ(result.warnings.size(), 2u);
  for (const std::string& warning : result.warnings) {
    EXPECT_EQ(warning.find("ambiguous"), std::string::npos) << warning;
  }
  const AlignedBox box = result.mesh.Bounds();
  EXPECT_NEAR(box.max.y(), 0.0, 1e-6);
  EXPECT_NEAR(box.Center().x(), 0.0, 1e-6);
  EXPECT_NEAR(box.Center().z(), 0.0, 1e-6);
}

TEST(Canonicalize, AutoForwardIsTheLongestHorizontalExtent) {
  // Given up = +z; the horizontal axes are x (1.8) and y (4.5).
  CanonicalizeOptions options;
  options.up = "+z";
  options.scale = 0.01;
  const CanonicalizeResult result = Canonicalize(CentimetreCarBox(), options);
  EXPECT_EQ(result.forward, "+y");
  EXPECT_TRUE(result.size.isApprox(Eigen::Vector3d(4.5, 1.5, 1.8), 1e-6));
  ASSERT_EQ(result.warnings.size(), 1u);
  EXPECT_NE(result.warnings[0].find("sign"), std::string::npos);
}

TEST(Canonicalize, WarnsWhenHeightAndWidthAreAmbiguous) {
  // A van: height 1.75 vs width 1.8 (within 10 %).
  const Mesh mesh = MakeBoxMesh(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(4.5, 1.75, 1.8));
  const CanonicalizeResult result = Canonicalize(mesh, CanonicalizeOptions());
  EXPECT_EQ(result.up, "+y");
  bool ambiguous = false;
  for (const std::string& warning : result.warnings) ambiguous |= warning.find("ambiguous") != std::string::npos;
  EXPECT_TRUE(ambiguous);
}

TEST(Canonicalize, RejectsImplausibleSizesNamingThem) {
  CanonicalizeOptions options;  // no scale: centimetres taken as metres
  options.up = "+z";
  options.forward = "-y";
  ExpectError([&] { Canonicalize(CentimetreCarBox(), options); },
                        {"implausible", "450.000", "150.000", "180.000"});
  options.scale = 0.001;  // ten times too small
  ExpectError([&] { Canonicalize(CentimetreCarBox(), options); }, {"0.450"});
  EXPECT_THROW(Canonicalize(Mesh(), CanonicalizeOptions()), Error);
}

TEST(Canonicalize, OptionsCheckNamesTheField) {
  CanonicalizeOptions options;
  options.scale = 0.01;
  options.target_length = 4.0;
  ExpectError([&] { options.Check(); }, {"target_length"});
  options = CanonicalizeOptions();
  options.up = "up";
  ExpectError([&] { options.Check(); }, {"up"});
  options = CanonicalizeOptions();
  options.up = "+y";
  options.forward = "-y";
  ExpectError([&] { options.Check(); }, {"different axes"});
  options = CanonicalizeOptions();
  options.scale = -1;
  ExpectError([&] { options.Check(); }, {"scale"});
}

TEST(Manifest, ParsesDefaultsEntriesAndFinds) {
  const fs::path dir = test::TempDir("manifest");
  const fs::path path = dir / "manifest.json";
  test::WriteText(path, R"({
    "comment": "test manifest",
    "models": [
      {"file": "cars/a/a.acc", "target_length": 4.2, "forward": "-y"},
      {"file": "b.obj", "name": "bee", "up": "+y", "forward": "+z", "min_size": [1, 0.5, 0.5], "wheels": "synthesise"},
      {"file": "f1.acc", "skip": true, "skip_reason": "open-wheel race car"}
    ],
    "defaults": {"scale": 0.01, "up": "+z"}
  })");
  const Manifest manifest = LoadManifest(path.string());
  EXPECT_DOUBLE_EQ(*manifest.defaults.scale, 0.01);
  EXPECT_EQ(manifest.defaults.up, "+z");
  EXPECT_EQ(manifest.defaults.forward, "auto");
  ASSERT_EQ(manifest.entries.size(), 3u);
  const ManifestEntry& a = manifest.entries[0];
  EXPECT_EQ(a.name, "a");
  EXPECT_FALSE(a.canonicalize.scale.has_value());  // target_length replaces the default scale
  EXPECT_DOUBLE_EQ(*a.canonicalize.target_length, 4.2);
  EXPECT_EQ(a.canonicalize.up, "+z");
  EXPECT_EQ(a.canonicalize.forward, "-y");
  const ManifestEntry& b = manifest.entries[1];
  EXPECT_EQ(b.name, "bee");
  EXPECT_DOUBLE_EQ(*b.canonicalize.scale, 0.01);
  EXPECT_EQ(b.canonicalize.up, "+y");
  EXPECT_TRUE(b.canonicalize.min_size.isApprox(Eigen::Vector3d(1, 0.5, 0.5)));
  EXPECT_TRUE(b.canonicalize.add_wheels);
  EXPECT_FALSE(a.canonicalize.add_wheels);
  EXPECT_TRUE(manifest.entries[2].skip);
  EXPECT_EQ(manifest.entries[2].skip_reason, "open-wheel race car");

  EXPECT_EQ(manifest.Find("cars/a/a.acc"), &a);
  EXPECT_EQ(manifest.Find("cars/./a/a.acc"), &a);
  EXPECT_EQ(manifest.Find("a.acc"), &a);  // by file name
  EXPECT_EQ(manifest.Find("sub/b.obj"), &b);
  EXPECT_EQ(manifest.Find("c.obj"), nullptr);
  fs::remove_all(dir);
}

TEST(Manifest, ErrorsNameTheFileAndField) {
  const fs::path dir = test::TempDir("manifest_errors");
  const fs::path path = dir / "m.json";
  const std::string file = path.string();
  struct Case {
    std::string json;
    std::vector<std::string> parts;
  };
  const std::vector<Case> cases = {
      {R"({"models": [{"file": "a.obj", "scael": 0.01}]})", {file, "models[0].scael", "unknown key"}},
      {R"({"models": [{"file": "a.obj", "up": "z"}]})", {file, "models[0].up"}},
      {R"({"models": [{"file": "a.obj"}, {"file": "b.obj", "scale": -2}]})", {file, "models[1].scale"}},
      {R"({"models": [{"file": "a.obj", "scale": "big"}]})", {file, "models[0].scale", "number"}},
      {R"({"models": [{"file": "a.obj", "scale": 1, "target_length": 4}]})", {file, "models[0]", "not both"}},
      {R"({"models": [{"file": "a.obj", "up": "+y", "forward": "-y"}]})", {file, "models[0]", "different axes"}},
      {R"({"models": [{"name": "x"}]})", {file, "models[0].file", "missing"}},
      {R"({"models": [{"file": "a.obj", "skip": "yes"}]})", {file, "models[0].skip"}},
      {R"({"models": [{"file": "a.obj", "min_size": [1, 2]}]})", {file, "models[0].min_size"}},
      {R"({"models": [{"file": "a.obj"}, {"file": "a.obj"}]})", {file, "duplicate file"}},
      {R"({"models": [{"file": "x/a.obj"}, {"file": "y/a.obj"}]})", {file, "duplicate name"}},
      {R"({"defaults": {"forward": "+q"}})", {file, "defaults.forward"}},
      {R"({"models": [{"file": "a.obj", "wheels": "yes"}]})", {file, "models[0].wheels", "synthesise"}},
      {R"({"defaults": {"scale": 1}, "model": []})", {file, "model", "unknown key"}},
      {R"({"models": {}})", {file, "models", "array"}},
      {R"([1, 2])", {file, "object"}},
      {R"({"models": [ {"file": "a.obj",} ]})", {file, "JSON"}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.json);
    test::WriteText(path, c.json);
    ExpectError([&] { LoadManifest(file); }, c.parts);
  }
  ExpectError([&] { LoadManifest((dir / "missing.json").string()); }, {"missing.json"});
  fs::remove_all(dir);
}

}  // namespace
}  // namespace samp
