#include "libsamp/model/trainer.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "libsamp/core/error.h"
#include "libsamp/core/ply_io.h"
#include "libsamp/model/shape_lookup.h"
#include "libsamp/scan/mesh_io.h"
#include "libsamp/sdf/vdb_io.h"

namespace samp {
namespace {

namespace fs = std::filesystem;

class TrainerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() / ("samp_trainer_test_" + std::to_string(::getpid()));
    fs::remove_all(root_);
    cad_ = root_ / "cad";
    fs::create_directories(cad_ / "sub");
    // Car-sized shapes in a z-up CAD frame (x = length, y = width, z = height):
    // four boxes and two ellipsoids of different proportions, as OBJ and PLY.
    const double boxes[4][3] = {{4.2, 1.8, 1.5}, {4.8, 1.9, 1.4}, {3.8, 1.7, 1.6}, {4.5, 1.8, 1.3}};
    for (int i = 0; i < 4; ++i) {
      const Eigen::Vector3d half(boxes[i][0] / 2, boxes[i][1] / 2, boxes[i][2] / 2);
      const Mesh box = MakeBoxMesh(-half, half);
      const std::string name = "box" + std::to_string(i);
      if (i % 2 == 0) {
        ExportMesh((cad_ / (name + ".obj")).string(), box);
      } else {
        WritePly((cad_ / "sub" / (name + ".ply")).string(), box);
      }
    }
    const double ellipsoids[2][3] = {{4.4, 1.8, 1.5}, {4.0, 1.75, 1.35}};
    for (int i = 0; i < 2; ++i) {
      Mesh ellipsoid = MakeSphereMesh(Eigen::Vector3d::Zero(), 1.0, 12, 24);
      ellipsoid.Transform(Eigen::Affine3d(Eigen::Scaling(
          ellipsoids[i][0] / 2, ellipsoids[i][1] / 2, ellipsoids[i][2] / 2)));
      ExportMesh((cad_ / ("ellipsoid" + std::to_string(i) + ".obj")).string(), ellipsoid);
    }
    // A file assimp cannot read, one the manifest skips, and a non-mesh file.
    std::ofstream(cad_ / "broken.obj") << "this is not\na mesh \x01\x02 v v f 1 2\n";
    WritePly((cad_ / "sub" / "toy.ply").string(),
             MakeBoxMesh(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0.3, 0.2, 0.1)));
    std::ofstream(cad_ / "README.txt") << "not a mesh\n";

    manifest_ = (root_ / "manifest.json").string();
    std::ofstream(manifest_) << R"({
      "defaults": {"up": "+z", "forward": "+x"},
      "models": [
        {"file": "sub/toy.ply", "skip": true, "skip_reason": "a toy, not a car"},
        {"file": "ellipsoid1.obj", "name": "egg", "target_length": 4.1}
      ]
    })";

    options_.cad_folder = cad_.string();
    options_.manifest_path = manifest_;
    options_.output_path = (root_ / "out" / "model.vdb").string();
    options_.sdf_folder = (root_ / "sdf").string();
    options_.grid = GridSpec::CarDefault(0.2);
    options_.scan.num_views = 20;
    options_.scan.width = options_.scan.height = 64;
    options_.pca.num_components = 3;
    options_.show_progress = false;
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(root_, ec);
  }

  fs::path root_, cad_;
  std::string manifest_;
  TrainOptions options_;
};

const TrainedShape* FindShape(const TrainSummary& summary, const std::string& name) {
  for (const TrainedShape& s : summary.shapes) {
    if (s.name == name) return &s;
  }
  return nullptr;
}

// The SDF value at the voxel nearest to `p` of the model `name` written to `sdf_folder` (--sdf-dir); its grid in *spec.
float SdfValueAt(const std::string& sdf_folder, const std::string& name, const Eigen::Vector3d& p, GridSpec* spec) {
  VdbMetadata meta;
  const auto grids = ReadVdb((fs::path(sdf_folder) / (name + ".vdb")).string(), spec, &meta);
  const Eigen::Vector3i v = spec->ToVoxel(p).array().round().cast<int>();
  return grids.at(0).values.at(size_t(spec->Index(v.x(), v.y(), v.z())));
}

TEST_F(TrainerTest, TrainsFromAFolderAndSkipsBadFiles) {
  const TrainSummary summary = TrainShapeModel(options_);
  ASSERT_EQ(summary.shapes.size(), 8u) << summary.BriefReport();
  EXPECT_EQ(summary.num_used, 6) << summary.BriefReport();

  const TrainedShape* broken = FindShape(summary, "broken");
  ASSERT_NE(broken, nullptr);
  EXPECT_FALSE(broken->used);
  EXPECT_FALSE(broken->reject_reason.empty());
  const TrainedShape* toy = FindShape(summary, "toy");
  ASSERT_NE(toy, nullptr);
  EXPECT_FALSE(toy->used);
  EXPECT_NE(toy->reject_reason.find("a toy, not a car"), std::string::npos);
  const TrainedShape* egg = FindShape(summary, "egg");
  ASSERT_NE(egg, nullptr);
  EXPECT_TRUE(egg->used) << egg->reject_reason;
  EXPECT_NEAR(egg->size.x(), 4.1, 1e-6);  // manifest target_length
  const TrainedShape* box1 = FindShape(summary, "box1");
  ASSERT_NE(box1, nullptr);
  EXPECT_TRUE(box1->used) << box1->reject_reason;
  EXPECT_NEAR(box1->size.x(), 4.8, 1e-4);
  EXPECT_NEAR(box1->size.y(), 1.4, 1e-4);  // height
  EXPECT_NEAR(box1->size.z(), 1.9, 1e-4);  // width
  EXPECT_GT(box1->inside_fraction, 0.05);

  ASSERT_EQ(summary.eigenvalues.size(), 3);
  EXPECT_GT(summary.eigenvalues[0], summary.eigenvalues[1]);
  EXPECT_GT(summary.eigenvalues[2], 0.0);
  EXPECT_GT(summary.explained_variance, 0.5);
  EXPECT_LE(summary.explained_variance, 1.0 + 1e-9);
  const std::string report = summary.BriefReport();
  EXPECT_NE(report.find("broken"), std::string::npos) << report;
  EXPECT_NE(report.find("explained variance"), std::string::npos) << report;

  const ShapeModel model = ShapeModel::Load(options_.output_path);
  EXPECT_EQ(model.NumComponents(), 3);
  EXPECT_EQ(model.grid, options_.grid);
  EXPECT_EQ(model.training_shapes.size(), 6u);
  EXPECT_TRUE(model.eigenvalues.isApprox(summary.eigenvalues, 1e-12));
  const nlohmann::json stored = nlohmann::json::parse(model.options_json);
  EXPECT_EQ(stored["scan"]["num_views"], 20);
  EXPECT_EQ(stored["pca"]["num_components"], 3);
  // The mean shape is a car-sized blob around the origin's bottom centre.
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(3);
  const ShapeLookup lookup(model);
  EXPECT_LT(lookup.Evaluate(zero, Eigen::Vector3d(0, -0.7, 0)), -0.3);
  EXPECT_GT(lookup.Evaluate(zero, Eigen::Vector3d(2.8, -2.0, 1.2)), 0.3);

  // One SDF file per used model, with its provenance.
  int num_sdf_files = 0;
  for (const auto& entry : fs::directory_iterator(options_.sdf_folder)) {
    ++num_sdf_files;
    GridSpec spec;
    VdbMetadata meta;
    const auto grids = ReadVdb(entry.path().string(), &spec, &meta);
    ASSERT_EQ(grids.size(), 1u);
    EXPECT_EQ(grids[0].name, "sdf");
    EXPECT_EQ(spec, options_.grid);
    EXPECT_EQ(meta["samp_file_type"], "sdf");
    EXPECT_FALSE(meta["samp_source_file"].empty());
  }
  EXPECT_EQ(num_sdf_files, 6);
}

TEST_F(TrainerTest, FailsClearlyWithTooFewUsableModels) {
  options_.pca.num_components = 6;  // needs 7 usable models, there are 6
  try {
    TrainShapeModel(options_);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("only 6 of 8 models are usable"), std::string::npos)
        << e.what();
  }
  // Nothing half-written is left behind.
  EXPECT_FALSE(fs::exists(options_.output_path));
  if (fs::exists(fs::path(options_.output_path).parent_path())) {
    EXPECT_TRUE(fs::is_empty(fs::path(options_.output_path).parent_path()));
  }
}

// Issue 16: a symlink loop trained on copies of the same meshes. Links to
// folders already walked add nothing: still the 8 files of the folder.
TEST_F(TrainerTest, SymlinkLoopsAddNoCopies) {
  fs::create_directory_symlink(cad_, cad_ / "sub" / "loop");
  fs::create_directory_symlink(cad_ / "sub", cad_ / "again");
  options_.pca.num_components = 6;  // fails after the scans: the count of models is in the message
  try {
    TrainShapeModel(options_);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("only 6 of 8 models are usable"), std::string::npos)
        << e.what();
  }
}

TEST_F(TrainerTest, QualityGateSkipsAShapeInTwoPiecesAndListsIt) {
  // Two boxes 1.2 m apart: a 4.6 m "car" whose inside is two equal components.
  Mesh twins = MakeBoxMesh(Eigen::Vector3d(-2.3, -0.9, 0.0), Eigen::Vector3d(-0.6, 0.9, 1.4));
  twins.Append(MakeBoxMesh(Eigen::Vector3d(0.6, -0.9, 0.0), Eigen::Vector3d(2.3, 0.9, 1.4)));
  ExportMesh((cad_ / "twins.obj").string(), twins);
  const TrainSummary summary = TrainShapeModel(options_);
  EXPECT_EQ(summary.num_used, 6) << summary.BriefReport();
  const TrainedShape* shape = FindShape(summary, "twins");
  ASSERT_NE(shape, nullptr);
  EXPECT_FALSE(shape->used);
  EXPECT_NE(shape->reject_reason.find("SDF quality gate: largest inside component share 0.5"), std::string::npos)
      << shape->reject_reason;
  EXPECT_NEAR(shape->quality.largest_component, 0.5, 0.02);
  const std::string report = summary.BriefReport();
  EXPECT_NE(report.find("skipped by the quality gate: twins (largest inside component share"), std::string::npos)
      << report;
  // The boxes that were used passed the gate, filling most of their box.
  const TrainedShape* box0 = FindShape(summary, "box0");
  ASSERT_NE(box0, nullptr);
  EXPECT_TRUE(box0->quality.pass);
  EXPECT_GT(box0->quality.box_fill, 0.6);
  EXPECT_DOUBLE_EQ(box0->quality.largest_component, 1.0);
}

TEST_F(TrainerTest, ApolloCar3DPresetTrainsOnCarModelsJson) {
  // car_models_json files: metres, x across, y down, front +z, 1-based faces.
  const fs::path folder = root_ / "apollo" / "car_models_json";
  fs::create_directories(folder);
  const double sizes[4][3] = {{1.8, 1.5, 4.4}, {1.75, 1.45, 4.0}, {1.9, 1.7, 4.8}, {1.7, 1.4, 3.8}};
  for (int c = 0; c < 4; ++c) {
    const Eigen::Vector3d half(sizes[c][0] / 2, sizes[c][1] / 2, sizes[c][2] / 2);
    const Mesh box = MakeBoxMesh(-half, half);
    nlohmann::json j;
    j["car_type"] = "test";
    for (const Eigen::Vector3f& v : box.vertices) j["vertices"].push_back({v.x(), v.y(), v.z()});
    for (const Eigen::Vector3i& t : box.triangles) j["faces"].push_back({t[0] + 1, t[1] + 1, t[2] + 1});
    std::ofstream(folder / ("car" + std::to_string(c) + ".json")) << j.dump();
  }
  TrainOptions options = options_;
  options.cad_folder = (root_ / "apollo").string();
  options.manifest_path.clear();
  options.sdf_folder.clear();
  options.preset = "apollocar3d";
  const TrainSummary summary = TrainShapeModel(options);
  ASSERT_EQ(summary.num_used, 4) << summary.BriefReport();
  const TrainedShape* car2 = FindShape(summary, "car2");
  ASSERT_NE(car2, nullptr);
  EXPECT_NEAR(car2->size.x(), 4.8, 1e-4);  // length from Apollo z
  EXPECT_NEAR(car2->size.y(), 1.7, 1e-4);  // height from Apollo y
  EXPECT_NEAR(car2->size.z(), 1.9, 1e-4);  // width from Apollo x
  EXPECT_EQ(nlohmann::json::parse(ShapeModel::Load(options.output_path).options_json)["preset"], "apollocar3d");
  options.preset = "kitti";
  EXPECT_THROW(TrainShapeModel(options), Error);
}

// Size variants: one stretched copy of every usable car per variant, named
// after its factors, with the stretched size; the stretch keeps the bottom
// centre: a taller variant reaches higher and no lower.
TEST_F(TrainerTest, SizeVariantsAddStretchedCopiesOfEveryUsableCar) {
  options_.size_variants = {Eigen::Vector3d(1.1, 1.25, 1.05)};
  options_.sdf_folder.clear();
  const TrainSummary summary = TrainShapeModel(options_);
  EXPECT_EQ(summary.num_used, 12) << summary.BriefReport();
  const TrainedShape* box1 = FindShape(summary, "box1");
  const TrainedShape* tall = FindShape(summary, "box1@1.10x1.25x1.05");
  ASSERT_NE(box1, nullptr);
  ASSERT_NE(tall, nullptr) << summary.BriefReport();
  EXPECT_TRUE(tall->used) << tall->reject_reason;
  EXPECT_NEAR(tall->size.x(), 4.8 * 1.1, 1e-4);
  EXPECT_NEAR(tall->size.y(), 1.4 * 1.25, 1e-4);
  EXPECT_NEAR(tall->size.z(), 1.9 * 1.05, 1e-4);
  EXPECT_TRUE(tall->size_factors.isApprox(Eigen::Vector3d(1.1, 1.25, 1.05)));
  // A file the manifest skips gets no variant; an unreadable one's variant is skipped too.
  EXPECT_EQ(FindShape(summary, "toy@1.10x1.25x1.05"), nullptr);
  ASSERT_NE(FindShape(summary, "broken@1.10x1.25x1.05"), nullptr);
  EXPECT_FALSE(FindShape(summary, "broken@1.10x1.25x1.05")->used);
  const ShapeModel model = ShapeModel::Load(options_.output_path);
  EXPECT_EQ(model.training_shapes.size(), 12u);
  const TrainOptions stored = TrainOptionsFromJson(model.options_json, "model");
  ASSERT_EQ(stored.size_variants.size(), 1u);
  EXPECT_TRUE(stored.size_variants[0].isApprox(Eigen::Vector3d(1.1, 1.25, 1.05)));

  // The stretch keeps the bottom centre: in the SDFs of a variant 1.3 times
  // as tall (1.82 m), a point 1.6 m above the origin is inside, 0.2 m above
  // the ground still inside, and in the original (1.4 m) the first is outside.
  options_.size_variants = {Eigen::Vector3d(1.0, 1.3, 1.0)};
  options_.sdf_folder = (root_ / "sdf_variants").string();
  TrainShapeModel(options_);
  auto value_at = [&](const std::string& name, const Eigen::Vector3d& p) {
    GridSpec spec;
    return SdfValueAt(options_.sdf_folder, name, p, &spec);
  };
  EXPECT_LT(value_at("box1@1.00x1.30x1.00", Eigen::Vector3d(0, -1.6, 0)), 0.0f);
  EXPECT_LT(value_at("box1@1.00x1.30x1.00", Eigen::Vector3d(0, -0.2, 0)), 0.0f);
  EXPECT_GT(value_at("box1", Eigen::Vector3d(0, -1.6, 0)), 0.0f);

  options_.size_variants = {Eigen::Vector3d(0.2, 1.0, 1.0)};
  EXPECT_THROW(TrainShapeModel(options_), Error);
}

// A car longer than the grid is cut off at its faces; a longer grid
// (samp train --grid-length) keeps it whole, and the model file records it.
TEST_F(TrainerTest, ALongerGridKeepsALongCarWhole) {
  options_.size_variants = {Eigen::Vector3d(1.4, 1.0, 1.0)};  // box1: 6.72 m long, ends at x = +-3.36 m
  auto value_at = [&](const std::string& name, const Eigen::Vector3d& p, GridSpec* spec) {
    return SdfValueAt(options_.sdf_folder, name, p, spec);
  };
  const std::string stretched = "box1@1.40x1.00x1.00";
  const Eigen::Vector3d middle(0, -0.6, 0);
  // The default grid (x in [-3, 3]): the car is still inside at the grid's end faces.
  TrainShapeModel(options_);
  GridSpec spec;
  EXPECT_LT(value_at(stretched, Eigen::Vector3d(3.0, -0.6, 0), &spec), 0.0f);
  EXPECT_LT(value_at(stretched, Eigen::Vector3d(-3.0, -0.6, 0), &spec), 0.0f);
  EXPECT_EQ(spec, GridSpec::CarDefault(0.2));
  // A 7.6 m grid: inside up to its ends, outside beyond them, as far as the grid reaches.
  options_.grid = GridSpec::Car(7.6, 2.8, 2.8, 0.2);
  options_.output_path = (root_ / "out" / "long.vdb").string();
  options_.sdf_folder = (root_ / "sdf_long").string();
  TrainShapeModel(options_);
  EXPECT_LT(value_at(stretched, middle, &spec), 0.0f);
  EXPECT_LT(value_at(stretched, Eigen::Vector3d(3.2, -0.6, 0), &spec), 0.0f);
  EXPECT_GT(value_at(stretched, Eigen::Vector3d(3.6, -0.6, 0), &spec), 0.0f);
  EXPECT_GT(value_at(stretched, Eigen::Vector3d(-3.6, -0.6, 0), &spec), 0.0f);
  EXPECT_EQ(spec, GridSpec::Car(7.6, 2.8, 2.8, 0.2));
  const ShapeModel model = ShapeModel::Load(options_.output_path);
  EXPECT_EQ(model.grid, GridSpec::Car(7.6, 2.8, 2.8, 0.2));
  EXPECT_EQ(TrainOptionsFromJson(model.options_json, "long.vdb").grid, model.grid);
}

TEST_F(TrainerTest, RejectsBadOptionsAndFolders) {
  TrainOptions options = options_;
  options.cad_folder = (root_ / "does_not_exist").string();
  EXPECT_THROW(TrainShapeModel(options), Error);
  options = options_;
  options.output_path.clear();
  EXPECT_THROW(TrainShapeModel(options), Error);
  options = options_;
  options.num_threads = -1;
  EXPECT_THROW(TrainShapeModel(options), Error);
  options = options_;
  options.cad_folder = (root_ / "out_empty").string();
  fs::create_directories(options.cad_folder);
  EXPECT_THROW(TrainShapeModel(options), Error);
}

// `samp train -o` onto one of its own input meshes (or the manifest, or a
// hard link to a mesh) is refused before
// anything is computed, and the input stays byte-identical.
TEST_F(TrainerTest, RefusesToWriteOverItsInputs) {
  const std::string mesh = (cad_ / "ellipsoid0.obj").string();
  std::ifstream in(mesh, std::ios::binary);
  const std::string before((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto error_of = [](const TrainOptions& options) {
    try {
      TrainShapeModel(options);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  TrainOptions options = options_;
  options.output_path = (cad_ / "sub" / ".." / "ellipsoid0.obj").string();
  EXPECT_NE(error_of(options).find("is the input mesh " + mesh), std::string::npos) << error_of(options);
  options.output_path = manifest_;
  EXPECT_NE(error_of(options).find("is the manifest"), std::string::npos);
  const std::string link = (root_ / "link.obj").string();
  fs::create_hard_link(mesh, link);
  options.output_path = link;
  EXPECT_NE(error_of(options).find("is the input mesh " + mesh), std::string::npos) << error_of(options);
  std::ifstream again(mesh, std::ios::binary);
  EXPECT_EQ(std::string((std::istreambuf_iterator<char>(again)), std::istreambuf_iterator<char>()), before);
  EXPECT_FALSE(fs::exists(options_.output_path));
}

// The trainer options stored in a model file have one reader beside their
// writer: it reads back every option written, and a missing key is an error
// naming the source and the key.
TEST(TrainOptionsJson, ReadsBackWhatIsWrittenAndRejectsMissingKeys) {
  TrainOptions o;
  o.cad_folder = "cars";
  o.manifest_path = "cars/cad_manifest.json";
  o.grid = GridSpec::CarDefault(0.2);
  o.scan.num_views = 17;
  o.scan.fov_deg = 33.0;
  o.sdf.truncation = 0.4;
  o.sdf.carve_margin = 0.02;
  o.pca.num_components = 4;
  o.size_variants = {Eigen::Vector3d(1.1, 1.2, 1.05)};
  const TrainOptions read = TrainOptionsFromJson(o.ToJson(), "test");
  EXPECT_EQ(read.ToJson(), o.ToJson());
  EXPECT_EQ(read.grid, o.grid);
  EXPECT_EQ(read.scan.num_views, 17);
  EXPECT_EQ(read.sdf.carve_margin, 0.02);

  nlohmann::json j = nlohmann::json::parse(o.ToJson());
  j["sdf"].erase("carve_margin");
  try {
    TrainOptionsFromJson(j.dump(), "model.vdb");
    ADD_FAILURE() << "a missing key was accepted";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("model.vdb"), std::string::npos) << message;
    EXPECT_NE(message.find("sdf"), std::string::npos) << message;
    EXPECT_NE(message.find("'carve_margin'"), std::string::npos) << message;
  }
  // Files from before size variants have no key: none were used.
  j = nlohmann::json::parse(o.ToJson());
  j.erase("size_variants");
  EXPECT_TRUE(TrainOptionsFromJson(j.dump(), "old.vdb").size_variants.empty());
}

}  // namespace
}  // namespace samp
