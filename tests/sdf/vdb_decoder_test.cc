// samp's own decoder of .vdb grid payloads (libsamp/sdf/vdb_payload.h):
// (1) on trusted files it gives exactly the values OpenVDB's reader gives;
// (2) on files whose payload fields were forged and whose file checksum was
//     then recomputed (as libFuzzer or an attacker does), it throws the
//     specific samp::Error instead of crashing or allocating without bound.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <set>

#include <openvdb/openvdb.h>
#include <openvdb/tools/Dense.h>

#include "libsamp/core/error.h"
#include "libsamp/sdf/vdb_io.h"
#include "libsamp/sdf/vdb_io_testing.h"

namespace samp {
namespace {

namespace fs = std::filesystem;

fs::path TempDir(const std::string& name) {
  fs::path dir = fs::temp_directory_path() /
                 ("samp_vdb_decoder_test_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string ReadBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void WriteBytes(const fs::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), std::streamsize(bytes.size()));
}

std::string LoadError(const std::string& path) {
  try {
    ReadVdb(path, nullptr, nullptr);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

// OpenVDB's own reader (the reference on trusted files): each grid's values
// on the box [0, dims), background where the tree has none.
std::vector<DenseGrid> ReadWithOpenVdb(const std::string& path, const Eigen::Vector3i& dims) {
  InitializeOpenVdb();
  openvdb::io::File file(path);
  file.open(/*delayLoad=*/false);
  openvdb::GridPtrVecPtr grids = file.getGrids();
  file.close();
  const openvdb::CoordBBox bbox(openvdb::Coord(0, 0, 0),
                                openvdb::Coord(dims.x() - 1, dims.y() - 1, dims.z() - 1));
  std::vector<DenseGrid> out;
  for (const auto& base : *grids) {
    const auto grid = openvdb::gridConstPtrCast<openvdb::FloatGrid>(base);
    DenseGrid dense_grid;
    dense_grid.name = grid->getName();
    dense_grid.values.assign(size_t(dims.prod()), grid->background());
    openvdb::tools::Dense<float, openvdb::tools::LayoutXYZ> dense(bbox, dense_grid.values.data());
    openvdb::tools::copyToDense(*grid, dense);
    out.push_back(std::move(dense_grid));
  }
  return out;
}

// Bit-for-bit comparison of samp's decoder with OpenVDB's reader.
void ExpectSameAsOpenVdb(const std::string& path, const VdbReadOptions& options = VdbReadOptions()) {
  GridSpec spec;
  const std::vector<DenseGrid> ours = ReadVdb(path, &spec, nullptr, options);
  const std::vector<DenseGrid> theirs = ReadWithOpenVdb(path, spec.dims);
  ASSERT_EQ(ours.size(), theirs.size()) << path;
  // OpenVDB's File::getGrids orders the grids by name.
  std::map<std::string, const DenseGrid*> by_name;
  for (const DenseGrid& g : theirs) by_name[g.name] = &g;
  for (const DenseGrid& g : ours) {
    ASSERT_TRUE(by_name.count(g.name)) << g.name;
    const DenseGrid& reference = *by_name.at(g.name);
    ASSERT_EQ(g.values.size(), reference.values.size());
    ASSERT_EQ(std::memcmp(g.values.data(), reference.values.data(), g.values.size() * sizeof(float)),
              0)
        << path << ": grid '" << g.name << "' differs from OpenVDB's reader";
  }
}

// A smooth SDF-like field (it compresses, as samp's grids do), 0 far away.
std::vector<float> SphereField(const GridSpec& spec, double radius, float cutoff) {
  std::vector<float> values(size_t(spec.NumVoxels()));
  const Eigen::Vector3d centre = 0.5 * spec.dims.cast<double>();
  for (int k = 0; k < spec.dims.z(); ++k) {
    for (int j = 0; j < spec.dims.y(); ++j) {
      for (int i = 0; i < spec.dims.x(); ++i) {
        const double d = (Eigen::Vector3d(i, j, k) - centre).norm() - radius;
        values[size_t(spec.Index(i, j, k))] = std::abs(d) > cutoff ? 0.0f : float(d * 0.05);
      }
    }
  }
  return values;
}

// A dense SDF-like field (as samp's model grids are) with a sprinkling of
// background voxels, so that every leaf has active and inactive voxels.
std::vector<float> SdfWithHoles(const GridSpec& spec) {
  std::vector<float> values = SphereField(spec, 11.0, 1e9f);
  for (int k = 0; k < spec.dims.z(); ++k) {
    for (int j = 0; j < spec.dims.y(); ++j) {
      for (int i = 0; i < spec.dims.x(); ++i) {
        if ((i + 2 * j + 3 * k) % 7 == 0) values[size_t(spec.Index(i, j, k))] = 0.0f;
      }
    }
  }
  return values;
}

GridSpec Spec(int nx, int ny, int nz) {
  GridSpec spec;
  spec.origin = Eigen::Vector3d(-1.5, -0.75, 0.3);
  spec.voxel_size = 0.05;
  spec.dims = Eigen::Vector3i(nx, ny, nz);
  return spec;
}

const char* Name(VdbTestCompression c) { return c == VdbTestCompression::kBlosc ? "blosc" : "zip"; }

TEST(VdbDecoder, ShippedModelMatchesOpenVdb) {
  const std::string path = SAMP_SHIPPED_MODEL;
  ExpectSameAsOpenVdb(path);
  GridSpec spec;
  VdbMetadata meta;
  ReadVdb(path, &spec, &meta);
  EXPECT_EQ(meta.at("samp_grid_dims"), "61 29 29");
  // The voxel size as OpenVDB's index-to-world map gives it (the reader
  // before samp's decoder): (0.1 + -3) - -3 = 0.10000000000000009.
  EXPECT_EQ(spec.voxel_size, (0.1 + spec.origin.x()) - spec.origin.x());
  EXPECT_NEAR(spec.voxel_size, std::stod(meta.at("samp_grid_voxel_size")), 1e-12);
}

TEST(VdbDecoder, WrittenGridsMatchOpenVdb) {
  const fs::path dir = TempDir("match");
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> uniform(-3.0f, 3.0f);
  for (VdbTestCompression compression : {VdbTestCompression::kBlosc, VdbTestCompression::kZip}) {
    SCOPED_TRACE(Name(compression));
    // Random sparse values, a smooth field, a full grid, only the box's
    // edges, a grid spanning two upper internal nodes, and constant blocks
    // (stored as active tiles).
    const GridSpec spec = Spec(37, 21, 19);
    std::vector<DenseGrid> grids(5);
    grids[0].name = "sparse";
    grids[1].name = "smooth";
    grids[2].name = "full";
    grids[3].name = "edges";
    grids[4].name = "negative_zero";
    for (auto& g : grids) g.values.assign(size_t(spec.NumVoxels()), 0.0f);
    grids[1].values = SphereField(spec, 6.0, 3.0f);
    for (int k = 0; k < spec.dims.z(); ++k) {
      for (int j = 0; j < spec.dims.y(); ++j) {
        for (int i = 0; i < spec.dims.x(); ++i) {
          const size_t v = size_t(spec.Index(i, j, k));
          if (rng() % 10 == 0) grids[0].values[v] = uniform(rng);
          grids[2].values[v] = uniform(rng);
          const bool edge = i == 0 || j == 0 || k == 0 || i == spec.dims.x() - 1 ||
                            j == spec.dims.y() - 1 || k == spec.dims.z() - 1;
          if (edge) grids[3].values[v] = 1.0f + float(v % 5);
          grids[4].values[v] = (v % 3 == 0) ? -0.0f : (v % 3 == 1 ? 0.5f : 0.0f);
        }
      }
    }
    const std::string path = (dir / (std::string("grids_") + Name(compression) + ".vdb")).string();
    WriteVdbForTesting(path, spec, grids, {}, 0.0f, compression);
    ExpectSameAsOpenVdb(path);
    const auto read = ReadVdb(path, nullptr, nullptr);
    for (size_t g = 0; g < grids.size(); ++g) {
      for (size_t v = 0; v < grids[g].values.size(); ++v) {
        ASSERT_EQ(read[g].values[v], grids[g].values[v]) << grids[g].name << " voxel " << v;
      }
    }

    // Nothing but the background: an empty tree.
    const std::string empty = (dir / (std::string("empty_") + Name(compression) + ".vdb")).string();
    WriteVdbForTesting(empty, spec, {{"empty", std::vector<float>(size_t(spec.NumVoxels()), 0.25f)}},
                       {}, 0.25f, compression);
    ExpectSameAsOpenVdb(empty);

    // Two upper internal nodes (x beyond 4096), values at both ends.
    const GridSpec wide = Spec(4100, 2, 3);
    std::vector<float> wide_values(size_t(wide.NumVoxels()), 0.0f);
    for (int x : {0, 1, 4094, 4095, 4096, 4099}) wide_values[size_t(wide.Index(x, 1, 2))] = float(x);
    const std::string wide_path = (dir / (std::string("wide_") + Name(compression) + ".vdb")).string();
    WriteVdbForTesting(wide_path, wide, {{"wide", wide_values}}, {}, 0.0f, compression);
    ExpectSameAsOpenVdb(wide_path);

    // Constant 128^3 and 8^3 blocks: tiles of both internal levels, active.
    const GridSpec block = Spec(136, 130, 129);
    std::vector<float> block_values(size_t(block.NumVoxels()), 2.0f);
    for (int i = 128; i < 136; ++i) block_values[size_t(block.Index(i, 129, 128))] = -1.0f;
    const std::string block_path = (dir / (std::string("tiles_") + Name(compression) + ".vdb")).string();
    WriteVdbForTesting(block_path, block, {{"tiles", block_values}}, {}, 0.0f, compression);
    VdbReadOptions options;
    options.max_expansion = 1e6;
    ExpectSameAsOpenVdb(block_path, options);
  }
}

// Inactive values other than the background (which copyFromDense never
// writes) exercise every per-node metadata byte of OpenVDB's mask
// compression. The file is written by OpenVDB with samp's file metadata and
// sealed like a samp file.
TEST(VdbDecoder, EveryInactiveValueCodeMatchesOpenVdb) {
  InitializeOpenVdb();
  const fs::path dir = TempDir("codes");
  const float bg = 2.0f;
  const Eigen::Vector3i dims(72, 24, 17);
  for (VdbTestCompression compression : {VdbTestCompression::kBlosc, VdbTestCompression::kZip}) {
    SCOPED_TRACE(Name(compression));
    openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create(bg);
    grid->setName("codes");
    auto transform = openvdb::math::Transform::createLinearTransform(0.25);
    transform->postTranslate(openvdb::Vec3d(1.0, -2.0, 0.5));
    grid->setTransform(transform);
    openvdb::FloatTree& tree = grid->tree();
    // Leaf l at (8 l, 8, 0): its inactive values follow pattern l.
    const float patterns[7][3] = {{bg, bg, bg},    {-bg, -bg, -bg}, {7, 7, 7},  {-bg, bg, bg},
                                  {7, bg, 7},      {7, 9, 9},       {1, 3, 5}};
    for (int l = 0; l < 7; ++l) {
      auto* leaf = tree.touchLeaf(openvdb::Coord(8 * l, 8, 0));
      for (openvdb::Index n = 0; n < leaf->SIZE; ++n) {
        if (n % 5 == 0) {
          leaf->setValueOn(n, float(n) * 0.01f - 1.0f);
        } else {
          leaf->setValueOff(n, patterns[l][n % 3]);
        }
      }
    }
    // Leaves that are all active and all inactive; tiles of both internal
    // levels, active and inactive, background and not.
    auto* full = tree.touchLeaf(openvdb::Coord(56, 0, 8));
    for (openvdb::Index n = 0; n < full->SIZE; ++n) full->setValueOn(n, float(n));
    auto* dark = tree.touchLeaf(openvdb::Coord(64, 16, 8));
    for (openvdb::Index n = 0; n < dark->SIZE; ++n) dark->setValueOff(n, n % 2 ? 4.0f : -bg);
    tree.addTile(1, openvdb::Coord(0, 16, 8), 3.0f, true);
    tree.addTile(1, openvdb::Coord(8, 16, 8), -5.0f, false);
    tree.addTile(1, openvdb::Coord(16, 0, 8), -bg, false);
    EXPECT_GT(tree.activeTileCount(), 0u);

    openvdb::MetaMap meta;
    meta.insertMeta("samp_grid_dims", openvdb::StringMetadata("72 24 17"));
    meta.insertMeta("samp_grid_count", openvdb::StringMetadata("1"));
    meta.insertMeta("samp_file_bytes", openvdb::StringMetadata(std::string(20, '0')));
    meta.insertMeta("samp_file_checksum", openvdb::StringMetadata(std::string(16, '0')));
    const std::string path = (dir / (std::string("codes_") + Name(compression) + ".vdb")).string();
    openvdb::io::File file(path);
    file.setCompression((compression == VdbTestCompression::kBlosc ? openvdb::io::COMPRESS_BLOSC
                                                                   : openvdb::io::COMPRESS_ZIP) |
                        openvdb::io::COMPRESS_ACTIVE_MASK);
    file.write({grid}, meta);
    file.close();
    ResealVdbForTesting(path);

    ExpectSameAsOpenVdb(path);
    // Every code 0..6 was written (and decoded) for some leaf.
    const std::string bytes = ReadBytes(path);
    const auto layouts = VdbPayloadLayoutForTesting(path);
    ASSERT_EQ(layouts.size(), 1u);
    std::set<int> codes;
    for (const auto& leaf : layouts[0].leaves) codes.insert(int(int8_t(bytes[leaf.metadata])));
    EXPECT_EQ(codes, (std::set<int>{0, 1, 2, 3, 4, 5, 6}));
    GridSpec spec;
    ReadVdb(path, &spec, nullptr);
    EXPECT_EQ(spec.voxel_size, 0.25);
    EXPECT_EQ(spec.origin, Eigen::Vector3d(1.0, -2.0, 0.5));
  }
}

// ---- Hostile payloads ---------------------------------------------------------

template <typename T>
void Put(std::string* bytes, size_t at, T value) {
  ASSERT_LE(at + sizeof(T), bytes->size());
  std::memcpy(&(*bytes)[at], &value, sizeof(T));
}
template <typename T>
T Get(const std::string& bytes, size_t at) {
  T value;
  std::memcpy(&value, bytes.data() + at, sizeof(T));
  return value;
}

int CountBits(const std::string& bytes, size_t mask) {
  int count = 0;
  for (int w = 0; w < 8; ++w) count += __builtin_popcountll(Get<uint64_t>(bytes, mask + 8 * w));
  return count;
}

std::string LeafName(const VdbPayloadLayout::Leaf& leaf) {
  return "leaf at (" + std::to_string(leaf.origin.x()) + ", " + std::to_string(leaf.origin.y()) +
         ", " + std::to_string(leaf.origin.z()) + ")";
}

void SetBit(std::string* bytes, size_t mask, int n) {
  const size_t word = mask + 8 * size_t(n / 64);
  Put<uint64_t>(bytes, word, Get<uint64_t>(*bytes, word) | (uint64_t(1) << (n % 64)));
}

class HostilePayload : public ::testing::TestWithParam<VdbTestCompression> {
 protected:
  void SetUp() override {
    dir_ = TempDir(std::string("hostile_") + Name(GetParam()));
    valid_ = (dir_ / "valid.vdb").string();
    // An SDF-like grid on the shipped model's box: one upper and one lower
    // internal node, leaves cut by the box.
    spec_ = Spec(61, 29, 29);
    WriteVdbForTesting(valid_, spec_, {{"pc_2", SdfWithHoles(spec_)}}, {}, 0.0f, GetParam());
    original_ = ReadBytes(valid_);
    const auto layouts = VdbPayloadLayoutForTesting(valid_);
    ASSERT_EQ(layouts.size(), 1u);
    layout_ = layouts[0];
    ASSERT_EQ(layout_.root_child_origins.size(), 1u);
    ASSERT_EQ(layout_.internal_levels, (std::vector<int>{5, 4}));
    ASSERT_GT(layout_.leaves.size(), 10u);
  }

  // Writes `bytes` re-sealed (they pass the file checksum) and returns ReadVdb's error.
  std::string Forged(const std::string& bytes) {
    const std::string path = (dir_ / "forged.vdb").string();
    WriteBytes(path, bytes);
    ResealVdbForTesting(path);
    return LoadError(path);
  }

  // The first leaf whose chunk is compressed (positive size prefix).
  const VdbPayloadLayout::Leaf& CompressedLeaf() const {
    for (const auto& leaf : layout_.leaves) {
      if (leaf.chunk_bytes > 16) return leaf;
    }
    ADD_FAILURE() << "no compressed leaf";
    return layout_.leaves[0];
  }

  fs::path dir_;
  std::string valid_;
  GridSpec spec_;
  std::string original_;
  VdbPayloadLayout layout_;
};

#define EXPECT_ERROR(error, text)                                            \
  do {                                                                       \
    const std::string e_ = (error);                                          \
    EXPECT_NE(e_.find(text), std::string::npos) << "error: '" << e_ << "'"; \
    EXPECT_NE(e_.find("forged.vdb: grid 'pc_2'"), std::string::npos) << e_;  \
  } while (0)

TEST_P(HostilePayload, ValidFileLoads) {
  EXPECT_EQ(LoadError(valid_), "");
  // Re-sealing an unchanged file changes nothing.
  EXPECT_EQ(Forged(original_), "");
}

TEST_P(HostilePayload, RootCounts) {
  std::string bytes = original_;
  Put<uint32_t>(&bytes, layout_.child_count, 1000000);
  EXPECT_ERROR(Forged(bytes), "its root holds 0 tiles and 1000000 children, the 61 x 29 x 29 grid has room for 1");
  bytes = original_;
  Put<uint32_t>(&bytes, layout_.tile_count, 0xffffffffu);
  EXPECT_ERROR(Forged(bytes), "its root holds 4294967295 tiles and 1 children");
}

TEST_P(HostilePayload, NodeOriginsOutsideTheBox) {
  std::string bytes = original_;
  Put<int32_t>(&bytes, layout_.root_child_origins[0], 4096);
  EXPECT_ERROR(Forged(bytes), "internal node at (4096, 0, 0) outside the 61 x 29 x 29 grid");
  bytes = original_;
  Put<int32_t>(&bytes, layout_.root_child_origins[0] + 4, -4096);
  EXPECT_ERROR(Forged(bytes), "internal node at (0, -4096, 0) outside the 61 x 29 x 29 grid");
  bytes = original_;
  Put<int32_t>(&bytes, layout_.root_child_origins[0] + 8, 8);
  EXPECT_ERROR(Forged(bytes), "internal node at (0, 0, 8) is not on a multiple of 4096");

  // A lower internal node at (128, 0, 0): slot 1024 of the upper node's child mask.
  bytes = original_;
  const size_t upper_mask = layout_.internal_child_masks[0];
  SetBit(&bytes, upper_mask, 1 << 10);
  EXPECT_ERROR(Forged(bytes), "lower internal node at (128, 0, 0) outside the 61 x 29 x 29 grid");

  // A leaf at (64, 8, 0): slot (8 << 8) + (1 << 4) = 2064 of the lower node's child mask.
  bytes = original_;
  const size_t lower_mask = layout_.internal_child_masks[1];
  SetBit(&bytes, lower_mask, (8 << 8) + (1 << 4));
  EXPECT_ERROR(Forged(bytes), "leaf at (64, 8, 0) outside the 61 x 29 x 29 grid");

  // An active 8^3 tile of the lower node at (64, 0, 0) (slot 8 << 8), and an
  // active 128^3 tile of the upper node at (0, 128, 0) (slot 1 << 5).
  bytes = original_;
  const size_t lower_values = lower_mask + 512;
  SetBit(&bytes, lower_values, 8 << 8);
  EXPECT_ERROR(Forged(bytes), "active tile of the lower internal node at (64, 0, 0) (side 8) reaches outside the 61 x 29 x 29 grid");
  bytes = original_;
  SetBit(&bytes, upper_mask + 4096, 1 << 5);
  EXPECT_ERROR(Forged(bytes), "active tile of the upper internal node at (0, 128, 0) (side 128) reaches outside");
  // A slot that is both a leaf and an active tile.
  bytes = original_;
  ASSERT_NE(Get<uint64_t>(bytes, lower_mask), 0u);
  Put<uint64_t>(&bytes, lower_values, Get<uint64_t>(bytes, lower_mask));
  EXPECT_ERROR(Forged(bytes), "lower internal node at (0, 0, 0) marks slots as both child and active tile");
}

TEST_P(HostilePayload, LeafMasks) {
  // A leaf at the box edge (x = 56..63, 61..63 outside the box).
  const VdbPayloadLayout::Leaf* edge = nullptr;
  for (const auto& leaf : layout_.leaves) {
    if (leaf.origin.x() == 56 && edge == nullptr) edge = &leaf;
  }
  ASSERT_NE(edge, nullptr);
  const std::string origin = LeafName(*edge);
  const int active = CountBits(original_, edge->topology_mask);
  // An inactive voxel inside the box (local x 0..4), made active in the
  // topology and the buffer alike: one more active bit than stored values.
  int inactive = -1;
  for (int n = 0; n < 5 * 64 && inactive < 0; ++n) {
    const int y = edge->origin.y() + (n >> 3) % 8, z = edge->origin.z() + n % 8;
    const bool set = (Get<uint64_t>(original_, edge->topology_mask + 8 * size_t(n / 64)) >> (n % 64)) & 1u;
    if (!set && y < 29 && z < 29) inactive = n;
  }
  ASSERT_GE(inactive, 0);
  std::string bytes = original_;
  SetBit(&bytes, edge->topology_mask, inactive);
  SetBit(&bytes, edge->buffer_mask, inactive);
  const std::string more = Forged(bytes);
  const std::string holds = std::to_string(4 * active + 4);
  if (edge->chunk_bytes > 0 && GetParam() == VdbTestCompression::kBlosc) {
    EXPECT_ERROR(more, "blosc chunk announces " + std::to_string(4 * active) + " bytes, " + origin +
                           " holds " + holds + " (" + std::to_string(active + 1) + " stored values)");
  } else if (edge->chunk_bytes > 0) {
    EXPECT_ERROR(more, "zip chunk of " + std::to_string(edge->chunk_bytes) + " bytes in " + origin +
                           " does not inflate to the " + holds + " bytes it holds");
  } else {
    EXPECT_ERROR(more, "uncompressed chunk of " + std::to_string(4 * active) + " bytes, " + origin +
                           " holds " + holds);
  }

  // An active voxel outside the box: local (7, 0, 0) is x = 63.
  bytes = original_;
  SetBit(&bytes, edge->topology_mask, 7 * 64);
  EXPECT_ERROR(Forged(bytes), origin + " has an active voxel at (63, " +
                                  std::to_string(edge->origin.y()) + ", " +
                                  std::to_string(edge->origin.z()) +
                                  ") outside the 61 x 29 x 29 grid");

  // The buffer's mask differs from the topology's.
  bytes = original_;
  SetBit(&bytes, edge->buffer_mask, inactive);
  EXPECT_ERROR(Forged(bytes), origin + " has a value mask in its buffer that differs from its topology");

  // An unknown per-node metadata byte.
  bytes = original_;
  bytes[edge->metadata] = 9;
  EXPECT_ERROR(Forged(bytes), origin + " has value metadata byte 9, OpenVDB writes 0 to 6");
}

TEST_P(HostilePayload, Chunks) {
  const VdbPayloadLayout::Leaf& leaf = CompressedLeaf();
  const std::string origin = LeafName(leaf);
  int stored = CountBits(original_, leaf.topology_mask);
  const int8_t code = int8_t(original_[leaf.metadata]);
  if (code == 6) stored = 512;
  const std::string holds = std::to_string(4 * stored);

  // A size prefix far beyond the grid's bytes.
  std::string bytes = original_;
  Put<int64_t>(&bytes, leaf.chunk_size, int64_t(1) << 40);
  EXPECT_ERROR(Forged(bytes), "needs 1099511627776 bytes");
  // A negative size (raw values) that disagrees with the mask; and INT64_MIN.
  bytes = original_;
  Put<int64_t>(&bytes, leaf.chunk_size, -9000000);
  EXPECT_ERROR(Forged(bytes), "uncompressed chunk of 9000000 bytes, " + origin + " holds " + holds);
  bytes = original_;
  Put<int64_t>(&bytes, leaf.chunk_size, std::numeric_limits<int64_t>::min());
  EXPECT_ERROR(Forged(bytes), "uncompressed chunk of 9223372036854775808 bytes");

  if (GetParam() == VdbTestCompression::kBlosc) {
    // A blosc header announcing far more than the leaf holds.
    bytes = original_;
    Put<uint32_t>(&bytes, leaf.chunk + 4, 9000000);
    EXPECT_ERROR(Forged(bytes), "blosc chunk announces 9000000 bytes, " + origin + " holds " + holds);
    // A truncated chunk: the size prefix shorter than the blosc header says.
    bytes = original_;
    Put<int64_t>(&bytes, leaf.chunk_size, leaf.chunk_bytes - 10);
    EXPECT_ERROR(Forged(bytes), "blosc chunk of " + origin + " says it is " +
                                    std::to_string(leaf.chunk_bytes) + " bytes long, its size prefix says " +
                                    std::to_string(leaf.chunk_bytes - 10));
    // Shorter than a blosc header.
    bytes = original_;
    Put<int64_t>(&bytes, leaf.chunk_size, 5);
    EXPECT_ERROR(Forged(bytes), "blosc chunk of 5 bytes in " + origin + ", shorter than its 16-byte header");
    // Corrupt compressed data behind a consistent header: blosc fails, no overrun.
    bytes = original_;
    for (int64_t b = 20; b < leaf.chunk_bytes; b += 3) bytes[leaf.chunk + size_t(b)] ^= 0x5a;
    const std::string garbled = Forged(bytes);
    EXPECT_NE(garbled.find("forged.vdb"), std::string::npos) << garbled;
  } else {
    // A truncated zip stream, then corrupt zip data.
    bytes = original_;
    Put<int64_t>(&bytes, leaf.chunk_size, leaf.chunk_bytes - 10);
    EXPECT_ERROR(Forged(bytes), "zip chunk of " + std::to_string(leaf.chunk_bytes - 10) + " bytes in " +
                                    origin + " does not inflate to the " + holds + " bytes it holds");
    bytes = original_;
    for (int64_t b = 2; b < leaf.chunk_bytes; b += 3) bytes[leaf.chunk + size_t(b)] ^= 0x5a;
    EXPECT_ERROR(Forged(bytes), "does not inflate");
  }
}

TEST_P(HostilePayload, TransformAndTree) {
  std::string bytes = original_;
  bytes[layout_.transform + 4 + 23] = 'q';  // UniformScaleTranslateMaq
  EXPECT_ERROR(Forged(bytes), "its transform is a 'UniformScaleTranslateMaq', samp reads only the UniformScaleTranslateMap");
  bytes = original_;
  Put<uint32_t>(&bytes, layout_.transform, 0xfffffff0u);
  EXPECT_ERROR(Forged(bytes), "its transform is a 'UniformScaleTranslateMap");
  // Scale fields: (0.05, 0.07, 0.05), and a negative one.
  const size_t fields = layout_.transform + 4 + 24;
  bytes = original_;
  Put<double>(&bytes, fields + 8 * 4, 0.07);
  EXPECT_ERROR(Forged(bytes), "is not one positive voxel size");
  bytes = original_;
  for (int a = 0; a < 3; ++a) Put<double>(&bytes, fields + 8 * (3 + a), -0.05);
  EXPECT_ERROR(Forged(bytes), "is not one positive voxel size");
  bytes = original_;
  Put<double>(&bytes, fields + 8 * 9, 19.0);  // inverse scale
  EXPECT_ERROR(Forged(bytes), "derived field 9 is 19");
  bytes = original_;
  Put<double>(&bytes, fields, std::nan(""));
  EXPECT_ERROR(Forged(bytes), "non-finite");
  // Buffer count and background.
  bytes = original_;
  Put<int32_t>(&bytes, layout_.background - 4, 2);
  EXPECT_ERROR(Forged(bytes), "its tree announces 2 buffers per node, samp writes 1");
  bytes = original_;
  Put<float>(&bytes, layout_.background, std::numeric_limits<float>::infinity());
  EXPECT_ERROR(Forged(bytes), "background value inf is not finite");
  // A different background passes the decoder but not the grid checksum.
  bytes = original_;
  Put<float>(&bytes, layout_.background, 0.5f);
  const std::string background = Forged(bytes);
  EXPECT_NE(background.find("fails its checksum"), std::string::npos) << background;
}

INSTANTIATE_TEST_SUITE_P(Compression, HostilePayload,
                         ::testing::Values(VdbTestCompression::kBlosc, VdbTestCompression::kZip),
                         [](const auto& info) { return std::string(Name(info.param)); });

// Two upper internal nodes, where the root's order matters.
TEST(VdbDecoder, RootChildrenTwiceOrOutOfOrder) {
  const fs::path dir = TempDir("root_order");
  const std::string path = (dir / "wide.vdb").string();
  const GridSpec wide = Spec(4100, 2, 3);
  std::vector<float> values(size_t(wide.NumVoxels()), 0.0f);
  values[size_t(wide.Index(1, 1, 1))] = 1.0f;
  values[size_t(wide.Index(4097, 1, 1))] = 2.0f;
  WriteVdb(path, wide, {{"wide", values}}, {});
  const auto layouts = VdbPayloadLayoutForTesting(path);
  ASSERT_EQ(layouts[0].root_child_origins.size(), 2u);
  std::string bytes = ReadBytes(path);
  Put<int32_t>(&bytes, layouts[0].root_child_origins[1], 0);  // the same node twice
  WriteBytes(path, bytes);
  ResealVdbForTesting(path);
  const std::string error = LoadError(path);
  EXPECT_NE(error.find("grid 'wide': internal node at (0, 0, 0) out of order or twice"),
            std::string::npos)
      << error;
}

}  // namespace
}  // namespace samp
