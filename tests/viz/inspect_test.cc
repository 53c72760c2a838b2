#include "libsamp/viz/inspect.h"

#include "libsamp/model/trainer.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>

#include "libsamp/core/error.h"
#include "libsamp/model/pca.h"
#include "libsamp/scan/mesh_io.h"
#include "libsamp/sdf/vdb_io.h"
#include "libsamp/sdf/surface.h"

namespace samp {
namespace {

namespace fs = std::filesystem;

// A fresh folder, removed at the end unless SAMP_KEEP_TEST_OUTPUT names a
// folder to keep the output in (to look at the pictures).
class TempFolder {
 public:
  explicit TempFolder(const std::string& name) {
    if (const char* keep = std::getenv("SAMP_KEEP_TEST_OUTPUT")) {
      path_ = fs::path(keep) / name;
      keep_ = true;
    } else {
      path_ = fs::temp_directory_path() / ("samp_viz_" + name + "_" + std::to_string(::getpid()));
    }
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempFolder() {
    if (!keep_) fs::remove_all(path_);
  }
  fs::path operator/(const std::string& name) const { return path_ / name; }
  std::string str() const { return path_.string(); }

 private:
  fs::path path_;
  bool keep_ = false;
};

GridSpec SphereGrid() {
  return GridSpec::FromBox(Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(1, 1, 1), 0.05);
}

// SDF of an axis-aligned ellipsoid-like shape: a sphere of radius r stretched by
// `stretch` along x (the exact SDF of a sphere when stretch = 1).
std::vector<float> ShapeSdf(const GridSpec& grid, double radius, double stretch = 1.0) {
  std::vector<float> values(grid.NumVoxels());
  for (int k = 0; k < grid.dims.z(); ++k)
    for (int j = 0; j < grid.dims.y(); ++j)
      for (int i = 0; i < grid.dims.x(); ++i) {
        Eigen::Vector3d p = grid.Position(i, j, k);
        p.x() /= stretch;
        values[grid.Index(i, j, k)] = float(p.norm() - radius);
      }
  return values;
}

// A model from training SDFs (one column each) by the model layer's PCA with
// R components; training shapes named prefix0, prefix1, ...
ShapeModel ModelFromSamples(const GridSpec& grid, const Eigen::MatrixXf& samples, int num_components,
                            const std::string& prefix) {
  PcaOptions pca_options;
  pca_options.num_components = num_components;
  const PcaResult pca = ComputePca(samples, pca_options);
  ShapeModel model;
  model.grid = grid;
  model.mean = pca.mean;
  model.components = pca.components;
  model.eigenvalues = pca.eigenvalues;
  model.total_variance = pca.total_variance;
  for (Eigen::Index n = 0; n < samples.cols(); ++n) model.training_shapes.push_back(prefix + std::to_string(n));
  model.Check();
  return model;
}

// A manifold of concentric spheres (radii 0.4 ... 0.7) built in memory with the
// model layer's PCA; R = 1 (the centred SDFs span one direction).
ShapeModel SphereModel(std::vector<std::vector<float>>* sdfs, std::vector<double>* radii) {
  const GridSpec grid = SphereGrid();
  *radii = {0.40, 0.48, 0.55, 0.62, 0.70};
  Eigen::MatrixXf samples(grid.NumVoxels(), radii->size());
  sdfs->clear();
  for (size_t n = 0; n < radii->size(); ++n) {
    sdfs->push_back(ShapeSdf(grid, (*radii)[n]));
    samples.col(n) = Eigen::Map<const Eigen::VectorXf>(sdfs->back().data(), grid.NumVoxels());
  }
  ShapeModel model = ModelFromSamples(grid, samples, 1, "sphere_");
  model.options_json = R"({"pca": {"num_components": 1}, "note": "spheres"})";
  return model;
}

// Two-parameter family (radius and stretch) for a model with R = 2.
ShapeModel EllipsoidModel(std::vector<std::vector<float>>* sdfs) {
  const GridSpec grid = SphereGrid();
  const std::vector<std::pair<double, double>> params = {
      {0.45, 1.0}, {0.55, 1.2}, {0.5, 1.4}, {0.6, 1.1}, {0.4, 1.3}, {0.52, 1.25}};
  Eigen::MatrixXf samples(grid.NumVoxels(), params.size());
  sdfs->clear();
  for (size_t n = 0; n < params.size(); ++n) {
    sdfs->push_back(ShapeSdf(grid, params[n].first, params[n].second));
    samples.col(n) = Eigen::Map<const Eigen::VectorXf>(sdfs->back().data(), grid.NumVoxels());
  }
  return ModelFromSamples(grid, samples, 3, "blob_");
}

void WriteSdf(const std::string& path, const GridSpec& grid, const std::vector<float>& sdf,
              const std::string& name) {
  WriteVdb(path, grid, {DenseGrid{"sdf", sdf}}, {{"samp_file_type", "sdf"}, {"samp_name", name}});
}

TEST(Inspect, SummaryOfSphereModel) {
  std::vector<std::vector<float>> sdfs;
  std::vector<double> radii;
  const ShapeModel model = SphereModel(&sdfs, &radii);
  const std::string text = SummarizeModel(model, "spheres.vdb");
  EXPECT_NE(text.find("format version 2"), std::string::npos) << text;
  EXPECT_NE(text.find("41 x 41 x 41 = 68921 voxels"), std::string::npos) << text;
  EXPECT_NE(text.find("components R     1"), std::string::npos) << text;
  EXPECT_NE(text.find("sphere_0, sphere_1, sphere_2, sphere_3, sphere_4"), std::string::npos) << text;
  EXPECT_NE(text.find("share of the total variance"), std::string::npos) << text;
  // Concentric spheres: one component explains (nearly) all of the variance.
  EXPECT_NE(text.find("100.00%"), std::string::npos) << text;
  EXPECT_NE(text.find("\"note\": \"spheres\""), std::string::npos) << text;

  ShapeModel without_total = model;
  without_total.total_variance = 0.0;
  EXPECT_NE(SummarizeModel(without_total).find("relative to the kept R components"),
            std::string::npos);
}

TEST(Inspect, MeanOfSpheresIsSphereOfMeanRadius) {
  std::vector<std::vector<float>> sdfs;
  std::vector<double> radii;
  const ShapeModel model = SphereModel(&sdfs, &radii);
  double mean_radius = 0;
  for (double r : radii) mean_radius += r / radii.size();
  const Mesh mean = ExtractSurface(model.grid, model.mean);
  ASSERT_FALSE(mean.Empty());
  for (const auto& v : mean.vertices) ASSERT_NEAR(v.norm(), mean_radius, 0.005);

  TempFolder folder("meshes");
  EigenShapeMeshOptions options;
  options.output_folder = folder.str();
  const EigenShapeMeshSummary summary = WriteEigenShapeMeshes(model, options);
  ASSERT_EQ(summary.files.size(), 3u) << summary.BriefReport();
  for (const char* name : {"mean.ply", "pc1_-2.0sd.ply", "pc1_+2.0sd.ply"}) {
    ASSERT_TRUE(fs::exists(folder / name)) << name;
  }
  const Mesh loaded = LoadMesh((folder / "mean.ply").string());
  EXPECT_NEAR(loaded.Bounds().Size().x(), 2 * mean_radius, 0.02);
  // +-2 sigma are spheres too, one smaller and one larger than the mean.
  const double r_minus = LoadMesh((folder / "pc1_-2.0sd.ply").string()).Bounds().Size().x() / 2;
  const double r_plus = LoadMesh((folder / "pc1_+2.0sd.ply").string()).Bounds().Size().x() / 2;
  EXPECT_GT(std::abs(r_plus - r_minus), 0.1);
  EXPECT_NEAR(0.5 * (r_plus + r_minus), mean_radius, 0.01);

  options.format = "glb";
  options.ks = {1.0};
  EXPECT_EQ(WriteEigenShapeMeshes(model, options).files.size(), 2u);
  EXPECT_TRUE(fs::exists(folder / "pc1_+1.0sd.glb"));
  options.format = "stl";
  EXPECT_THROW(WriteEigenShapeMeshes(model, options), Error);
}

TEST(Inspect, EncodeTrainingAndHeldOutShapes) {
  std::vector<std::vector<float>> sdfs;
  const ShapeModel model = EllipsoidModel(&sdfs);
  TempFolder folder("encode");
  WriteSdf((folder / "in" / "blob_2.vdb").string(), model.grid, sdfs[2], "blob_2");
  // Held out: inside the range of the training parameters, but not one of them.
  WriteSdf((folder / "in" / "held_out.vdb").string(), model.grid, ShapeSdf(model.grid, 0.5, 1.15),
           "held_out");
  EncodeOptions options;
  options.input = (folder / "in").string();
  options.output_folder = (folder / "out").string();
  const EncodeSummary summary = EncodeShapes(model, options);
  ASSERT_EQ(summary.shapes.size(), 2u);
  const EncodedShape& train = summary.shapes[0];
  ASSERT_TRUE(train.ok) << train.error;
  EXPECT_EQ(train.name, "blob_2");
  // A training shape lies in the manifold when R = N - 1... here R = 3 < 5, so
  // it is reconstructed up to the discarded variance: small errors.
  EXPECT_LT(train.rms_near_surface, 0.01) << summary.BriefReport();
  EXPECT_LT(train.accuracy.mean, 0.02) << summary.BriefReport();
  EXPECT_LT(train.completeness.p95, 0.05) << summary.BriefReport();
  EXPECT_GT(train.num_near_voxels, 100);
  ASSERT_TRUE(fs::exists(train.mesh_path));
  EXPECT_FALSE(LoadMesh(train.mesh_path).Empty());
  const EncodedShape& held_out = summary.shapes[1];
  ASSERT_TRUE(held_out.ok) << held_out.error;
  EXPECT_LT(held_out.rms_near_surface, 0.02) << summary.BriefReport();
  EXPECT_TRUE(fs::exists(folder / "out" / "encode.csv"));
  EXPECT_NE(summary.BriefReport().find("blob_2"), std::string::npos);

  // The prior pulls the code towards 0.
  const Eigen::VectorXd z0 = ProjectToManifold(model, sdfs[2]);
  const Eigen::VectorXd z1 = ProjectToManifold(model, sdfs[2], 10.0);
  EXPECT_LT(z1.norm(), z0.norm());

  // A file on another grid and a missing input.
  const GridSpec other = GridSpec::FromBox(Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(1, 1, 1), 0.1);
  WriteSdf((folder / "bad.vdb").string(), other, ShapeSdf(other, 0.5), "bad");
  options.input = (folder / "bad.vdb").string();
  options.output_folder.clear();
  const EncodeSummary bad = EncodeShapes(model, options);
  ASSERT_EQ(bad.shapes.size(), 1u);
  EXPECT_FALSE(bad.shapes[0].ok);
  EXPECT_NE(bad.shapes[0].error.find("differs from the model"), std::string::npos);
  options.input = (folder / "missing").string();
  EXPECT_THROW(EncodeShapes(model, options), Error);
}

TEST(Inspect, EncodeCadFile) {
  // A manifold of car-sized boxes standing on the ground in the canonical
  // frame (x length, y down with the bottom at y = 0, z width; exact box SDFs),
  // and a CAD box of a training size written as OBJ elsewhere, y up: encoding
  // loads it with assimp, canonicalises it, scans it with Embree, computes its
  // SDF on the model grid and projects it.
  const GridSpec grid = GridSpec::FromBox(Eigen::Vector3d(-2.6, -2.0, -1.3), Eigen::Vector3d(2.6, 0.4, 1.3), 0.1);
  const std::vector<Eigen::Vector3d> sizes = {{3.8, 1.4, 1.7}, {4.0, 1.6, 1.75}, {4.2, 1.5, 1.8},
                                              {4.4, 1.45, 1.9}, {4.6, 1.55, 1.85}};
  Eigen::MatrixXf samples(grid.NumVoxels(), Eigen::Index(sizes.size()));
  for (size_t n = 0; n < sizes.size(); ++n) {
    const Eigen::Vector3d half = 0.5 * sizes[n];
    for (int k = 0; k < grid.dims.z(); ++k)
      for (int j = 0; j < grid.dims.y(); ++j)
        for (int i = 0; i < grid.dims.x(); ++i) {
          const Eigen::Vector3d p = grid.Position(i, j, k) - Eigen::Vector3d(0, -half.y(), 0);
          const Eigen::Vector3d q = p.cwiseAbs() - half;
          const double sdf = q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
          samples(grid.Index(i, j, k), Eigen::Index(n)) = float(sdf);
        }
  }
  ShapeModel model = ModelFromSamples(grid, samples, 3, "box_");
  // Encoding a CAD file scans it with the model's stored trainer options.
  model.options_json = TrainOptions().ToJson();

  TempFolder folder("encode_cad");
  const std::string cad = (folder / "box.obj").string();
  ExportMesh(cad, MakeBoxMesh(Eigen::Vector3d(3.0, 2.0, -1.0), Eigen::Vector3d(7.2, 3.5, 0.8)));
  EncodeOptions options;
  options.input = cad;
  options.output_folder = (folder / "out").string();
  const EncodeSummary summary = EncodeShapes(model, options);
  ASSERT_EQ(summary.shapes.size(), 1u);
  const EncodedShape& box = summary.shapes[0];
  ASSERT_TRUE(box.ok) << box.error;
  EXPECT_EQ(box.kind, "cad");
  EXPECT_EQ(box.name, "box");
  // The code is that of the training box of the same size.
  const Eigen::VectorXf x = samples.col(2);
  const Eigen::VectorXd expected = ProjectToManifold(model, std::vector<float>(x.data(), x.data() + x.size()));
  ASSERT_EQ(box.code.size(), 3);
  for (int r = 0; r < 3; ++r) {
    EXPECT_NEAR(box.code[r], expected[r], 0.1 * std::sqrt(model.eigenvalues[0])) << summary.BriefReport();
  }
  EXPECT_LT(box.rms_near_surface, 0.05) << summary.BriefReport();
  EXPECT_LT(box.accuracy.mean, 0.05) << summary.BriefReport();
  EXPECT_LT(box.completeness.mean, 0.05) << summary.BriefReport();
  ASSERT_TRUE(fs::exists(box.mesh_path));
  EXPECT_FALSE(LoadMesh(box.mesh_path).Empty());
}

TEST(Inspect, NearestDistances) {
  const std::vector<Eigen::Vector3f> to = {{0, 0, 0}, {1, 0, 0}, {0, 2, 0}};
  const std::vector<Eigen::Vector3f> from = {{0.1f, 0, 0}, {1, 0.5f, 0}, {5, 5, 5}, {-3, 0, 0}};
  const DistanceStats stats = NearestDistances(from, to);
  EXPECT_EQ(stats.count, 4);
  EXPECT_NEAR(stats.max, Eigen::Vector3f(5, 3, 5).norm(), 1e-5);
  EXPECT_NEAR(stats.mean, (0.1 + 0.5 + Eigen::Vector3f(5, 3, 5).norm() + 3.0) / 4, 1e-5);
  // Sampling a unit sphere mesh: samples lie on it.
  const Mesh sphere = MakeSphereMesh(Eigen::Vector3d::Zero(), 1.0, 16, 32);
  const auto samples = SampleSurface(sphere, 1000, 7);
  ASSERT_EQ(samples.size(), 1000u);
  for (const auto& p : samples) EXPECT_LE(p.norm(), 1.0 + 1e-5);
  EXPECT_EQ(SampleSurface(sphere, 1000, 7), samples);  // seeded
}

TEST(Inspect, PicturesExistHaveTheExpectedSizeAndAreNotBlank) {
  std::vector<std::vector<float>> sdfs;
  const ShapeModel model = EllipsoidModel(&sdfs);
  TempFolder folder("pictures");
  for (size_t n = 0; n < sdfs.size(); ++n) {
    WriteSdf((folder / "sdf" / (model.training_shapes[n] + ".vdb")).string(), model.grid, sdfs[n],
             model.training_shapes[n]);
  }
  PictureOptions options;
  options.output_folder = (folder / "png").string();
  options.sdf_folder = (folder / "sdf").string();
  options.num_sheet_shapes = 3;
  const PictureSummary summary = WritePictures(model, options);
  ASSERT_EQ(summary.files.size(), 2u);
  // Layout (inspect_pictures.cc): margins 16, label column 170 (grid) / 150
  // (sheet), title 44, headers 30, gaps 6 (grid) / 8 (sheet), footer 18 (sheet).
  const RgbImage grid = ReadPng((folder / "png" / "eigen_shapes.png").string());
  EXPECT_EQ(grid.width, 16 + 170 + 5 * (300 + 6) - 6 + 16);
  EXPECT_EQ(grid.height, 44 + 30 + 3 * (170 + 6) - 6 + 16);
  EXPECT_GT(PixelVariance(grid), 200.0);
  const RgbImage sheet = ReadPng((folder / "png" / "shapes.png").string());
  EXPECT_EQ(sheet.width, 16 + 150 + 4 * (300 + 8) - 8 + 16);
  EXPECT_EQ(sheet.height, 44 + 30 + 3 * (170 + 18 + 8) - 8 + 16);
  EXPECT_GT(PixelVariance(sheet), 200.0);
  // Each rendered cell holds a shape: the centre of the first cell is not white.
  const int cx = 16 + 170 + 150, cy = 44 + 30 + 85;
  EXPECT_NE(grid.At(cx, cy), kWhite);

  const RgbImage slice = RenderSdfSlice(model.grid, sdfs[0], 4);
  EXPECT_EQ(slice.width, model.grid.dims.x() * 4);
  EXPECT_EQ(slice.height, model.grid.dims.y() * 4);
  EXPECT_GT(Diverging(-1.0).b, 0);
  // Inside at the centre (bluish), outside in the corner (reddish).
  const Rgb centre = slice.At(slice.width / 2, slice.height / 2), corner = slice.At(1, 1);
  EXPECT_GT(centre.b, centre.r);
  EXPECT_GT(corner.r, corner.b);
}

TEST(Inspect, NotAModelFileIsAClearError) {
  TempFolder folder("bad_model");
  const std::string path = (folder / "not_a_model.vdb").string();
  const GridSpec grid = SphereGrid();
  WriteSdf(path, grid, ShapeSdf(grid, 0.5), "x");
  try {
    ShapeModel::Load(path);
    FAIL() << "loading an SDF file as a model must fail";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace samp
