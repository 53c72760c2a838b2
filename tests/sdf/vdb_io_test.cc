#include "libsamp/sdf/vdb_io.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>

#include <openvdb/openvdb.h>

#include "libsamp/core/error.h"
#include "tests/testing/small_disk.h"

namespace samp {
namespace {

namespace fs = std::filesystem;

fs::path TempDir(const std::string& name) {
  fs::path dir = fs::temp_directory_path() /
                 ("samp_vdb_io_test_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

GridSpec TestSpec() {
  GridSpec spec;
  spec.origin = Eigen::Vector3d(-1.25, -0.7, 0.35);
  spec.voxel_size = 0.05;
  spec.dims = Eigen::Vector3i(13, 7, 5);
  return spec;
}

std::vector<DenseGrid> TestGrids(const GridSpec& spec) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> uniform(-2.0f, 2.0f);
  std::vector<DenseGrid> grids(3);
  grids[0].name = "mean";
  grids[1].name = "pc_0";
  grids[2].name = "sparse";
  for (auto& g : grids) g.values.resize(size_t(spec.NumVoxels()));
  for (size_t v = 0; v < grids[0].values.size(); ++v) {
    grids[0].values[v] = uniform(rng);
    grids[1].values[v] = uniform(rng);
    // Mostly background (0): inactive in the file, yet restored exactly.
    grids[2].values[v] = (v % 17 == 3) ? uniform(rng) : 0.0f;
  }
  // Non-background values at the corners of the box, where a bounding box
  // derived from active voxels would matter.
  grids[0].values.front() = 1.5f;
  grids[0].values.back() = -1.5f;
  return grids;
}

std::vector<char> ReadBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<char>(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void WriteBytes(const fs::path& path, const std::vector<char>& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), std::streamsize(bytes.size()));
}

TEST(VdbIo, RoundTripGridsAndMetadata) {
  const fs::path dir = TempDir("round_trip");
  const std::string path = (dir / "model.vdb").string();
  const GridSpec spec = TestSpec();
  const std::vector<DenseGrid> grids = TestGrids(spec);
  const VdbMetadata meta = {{"source", "cars/a b.obj"}, {"scale", "0.0254"}, {"json", "{\"R\": 5}"}};
  WriteVdb(path, spec, grids, meta);
  ASSERT_TRUE(fs::exists(path));
  // No temporary left beside the output.
  int files = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    (void)entry;
    ++files;
  }
  EXPECT_EQ(files, 1);

  GridSpec read_spec;
  read_spec.dims = Eigen::Vector3i(2, 2, 2);
  VdbMetadata read_meta;
  const std::vector<DenseGrid> read = ReadVdb(path, &read_spec, &read_meta);
  EXPECT_EQ(read_spec, spec) << read_spec.ToString() << " vs " << spec.ToString();
  EXPECT_EQ(read_spec.dims, spec.dims);
  ASSERT_EQ(read.size(), grids.size());
  for (size_t g = 0; g < grids.size(); ++g) {
    EXPECT_EQ(read[g].name, grids[g].name);
    ASSERT_EQ(read[g].values.size(), grids[g].values.size());
    for (size_t v = 0; v < grids[g].values.size(); ++v) {
      ASSERT_EQ(read[g].values[v], grids[g].values[v]) << grids[g].name << " voxel " << v;
    }
  }
  for (const auto& [key, value] : meta) {
    ASSERT_TRUE(read_meta.count(key)) << key;
    EXPECT_EQ(read_meta.at(key), value);
  }
  EXPECT_EQ(read_meta.at("samp_grid_dims"), "13 7 5");
}

// A model file on a disk without room for it: WriteVdb fails naming the file
// and the OS error, and the previous file stays byte-identical (the size and
// checksum fields were once computed over the truncated bytes, so the
// truncated file passed its checksum). A file that fits exactly is complete.
TEST(VdbIo, FullDiskLeavesThePreviousFile) {
  test::SmallDisk disk("vdb", 256 << 10);
  if (!disk.mounted()) GTEST_SKIP() << disk.reason();
  const std::string path = disk.path() + "/model.vdb";
  const GridSpec spec = TestSpec();
  const std::vector<DenseGrid> grids = TestGrids(spec);
  WriteVdb(path, spec, grids, {{"run", "good"}});
  const std::vector<char> good = ReadBytes(path);
  // Larger grids than the remaining space (random values compress badly).
  GridSpec big = spec;
  big.dims = Eigen::Vector3i(64, 48, 40);
  std::vector<DenseGrid> big_grids(2);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> uniform(-2.0f, 2.0f);
  for (size_t g = 0; g < big_grids.size(); ++g) {
    big_grids[g].name = "g" + std::to_string(g);
    big_grids[g].values.resize(size_t(big.NumVoxels()));
    for (float& v : big_grids[g].values) v = uniform(rng);
  }
  try {
    WriteVdb(path, big, big_grids, {{"run", "too big"}});
    ADD_FAILURE() << "writing " << 2 * big.NumVoxels() * 4 << " bytes of grids onto a 256 KiB disk did not fail";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(path), std::string::npos) << message;
    EXPECT_NE(message.find(std::strerror(ENOSPC)), std::string::npos) << message;
  }
  EXPECT_EQ(ReadBytes(path), good);
  VdbMetadata meta;
  ReadVdb(path, nullptr, &meta);
  EXPECT_EQ(meta.at("run"), "good");
  for (const auto& entry : fs::directory_iterator(disk.path())) {
    EXPECT_EQ(entry.path().filename().string(), "model.vdb") << "left behind";
  }
}

TEST(VdbIo, AllBackgroundGridKeepsItsSpec) {
  const fs::path dir = TempDir("background");
  const std::string path = (dir / "empty.vdb").string();
  const GridSpec spec = TestSpec();
  DenseGrid grid{"zero", std::vector<float>(size_t(spec.NumVoxels()), 0.25f)};
  WriteVdb(path, spec, {grid}, {}, /*background=*/0.25f);
  GridSpec read_spec;
  const auto read = ReadVdb(path, &read_spec, nullptr);
  EXPECT_EQ(read_spec, spec);
  ASSERT_EQ(read.size(), 1u);
  for (float v : read[0].values) ASSERT_EQ(v, 0.25f);
}

TEST(VdbIo, WriteRejectsBadInput) {
  const fs::path dir = TempDir("bad_input");
  const GridSpec spec = TestSpec();
  DenseGrid short_grid{"short", std::vector<float>(5, 1.0f)};
  EXPECT_THROW(WriteVdb((dir / "a.vdb").string(), spec, {short_grid}, {}), Error);
  DenseGrid good{"g", std::vector<float>(size_t(spec.NumVoxels()), 1.0f)};
  EXPECT_THROW(WriteVdb((dir / "b.vdb").string(), spec, {good, good}, {}), Error);
  EXPECT_THROW(WriteVdb((dir / "c.vdb").string(), spec, {}, {}), Error);
  EXPECT_TRUE(fs::is_empty(dir));
}

TEST(VdbIo, MissingFileIsAnError) {
  const fs::path dir = TempDir("missing");
  try {
    ReadVdb((dir / "nope.vdb").string(), nullptr, nullptr);
    FAIL() << "expected samp::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("nope.vdb"), std::string::npos) << e.what();
  }
}

TEST(VdbIo, GarbageFileIsAnError) {
  const fs::path dir = TempDir("garbage");
  const fs::path path = dir / "garbage.vdb";
  std::mt19937 rng(3);
  std::vector<char> bytes(4096);
  for (char& b : bytes) b = char(rng() & 0xff);
  WriteBytes(path, bytes);
  try {
    ReadVdb(path.string(), nullptr, nullptr);
    FAIL() << "expected samp::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("garbage.vdb"), std::string::npos) << e.what();
  }
  WriteBytes(path, {});
  EXPECT_THROW(ReadVdb(path.string(), nullptr, nullptr), Error);
}

TEST(VdbIo, TruncatedFileIsAnError) {
  const fs::path dir = TempDir("truncated");
  const fs::path path = dir / "model.vdb";
  const GridSpec spec = TestSpec();
  WriteVdb(path.string(), spec, TestGrids(spec), {{"source", "x"}});
  const std::vector<char> full = ReadBytes(path);
  ASSERT_GT(full.size(), 100u);
  // Cut at many places: the header, the metadata, inside the grids, the last byte.
  for (size_t cut : {size_t(4), size_t(40), size_t(200), full.size() / 4, full.size() / 3,
                     full.size() / 2, 2 * full.size() / 3, 3 * full.size() / 4, full.size() - 100,
                     full.size() - 4, full.size() - 1}) {
    WriteBytes(path, std::vector<char>(full.begin(), full.begin() + std::ptrdiff_t(cut)));
    EXPECT_THROW(ReadVdb(path.string(), nullptr, nullptr), Error) << "cut at " << cut;
  }
}

TEST(VdbIo, FlippedByteIsAnError) {
  const fs::path dir = TempDir("flipped");
  const fs::path path = dir / "model.vdb";
  const GridSpec spec = TestSpec();
  WriteVdb(path.string(), spec, TestGrids(spec), {});
  std::vector<char> bytes = ReadBytes(path);
  // A byte inside the (blosc-compressed) values of the last grid.
  bytes[bytes.size() - 50] ^= 0x5a;
  WriteBytes(path, bytes);
  EXPECT_THROW(ReadVdb(path.string(), nullptr, nullptr), Error);
}

TEST(VdbIo, ReservedMetadataKeysAreWrittenByWriteVdb) {
  const fs::path dir = TempDir("reserved");
  const GridSpec spec = TestSpec();
  const std::string path = (dir / "reserved.vdb").string();
  DenseGrid g{"g", std::vector<float>(size_t(spec.NumVoxels()), 1.0f)};
  WriteVdb(path, spec, {g}, {{"samp_grid_dims", "1 2"}});
  GridSpec read_spec;
  ReadVdb(path, &read_spec, nullptr);
  EXPECT_EQ(read_spec, spec);
}

std::string LoadError(const std::string& path, const VdbReadOptions& options = VdbReadOptions()) {
  try {
    ReadVdb(path, nullptr, nullptr, options);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

// OpenVDB's own reader is not safe on corrupt input, so files samp cannot
// verify are refused before OpenVDB decodes them.
TEST(VdbIo, FilesOfOtherToolsAreRefused) {
  InitializeOpenVdb();
  const fs::path dir = TempDir("foreign");
  const std::string path = (dir / "foreign.vdb").string();
  openvdb::FloatGrid::Ptr a = openvdb::FloatGrid::create(-1.0f);
  a->setName("a");
  a->tree().setValue(openvdb::Coord(2, -3, 4), 5.0f);
  a->setTransform(openvdb::math::Transform::createLinearTransform(0.5));
  openvdb::FloatGrid::Ptr b = a->deepCopy();
  b->setName("b");
  b->setTransform(openvdb::math::Transform::createLinearTransform(0.2));
  openvdb::io::File(path).write({a, b});
  const std::string error = LoadError(path);
  EXPECT_NE(error.find("not a samp .vdb file"), std::string::npos) << error;
  EXPECT_NE(error.find("foreign.vdb"), std::string::npos) << error;

  // A samp file of format 1 (metadata as before the file checksum): named as such.
  openvdb::MetaMap meta;
  meta.insertMeta("samp_file_type", openvdb::StringMetadata("shape_model"));
  meta.insertMeta("samp_format_version", openvdb::StringMetadata("1"));
  openvdb::io::File(path).write({a}, meta);
  const std::string old_error = LoadError(path);
  EXPECT_NE(old_error.find("format version 1"), std::string::npos) << old_error;
}

// Every byte of the file is covered by the checksum: whichever byte changes,
// the read fails with samp::Error before OpenVDB decodes anything.
TEST(VdbIo, EveryChangedByteIsAnError) {
  const fs::path dir = TempDir("every_byte");
  const fs::path path = dir / "model.vdb";
  GridSpec spec = TestSpec();
  spec.dims = Eigen::Vector3i(5, 4, 3);
  WriteVdb(path.string(), spec, TestGrids(spec), {{"source", "x"}});
  const std::vector<char> original = ReadBytes(path);
  ASSERT_NO_THROW(ReadVdb(path.string(), nullptr, nullptr));
  const fs::path corrupt = dir / "corrupt.vdb";
  // Every byte of the header and metadata, then every 7th (the file is ~35 kB).
  for (size_t at = 0; at < original.size(); at += at < 3000 ? 1 : 7) {
    std::vector<char> bytes = original;
    bytes[at] = char(bytes[at] ^ (at % 7 == 0 ? 0x80 : 0x01));
    WriteBytes(corrupt, bytes);
    ASSERT_FALSE(LoadError(corrupt.string()).empty()) << "byte " << at << " went unnoticed";
  }
}

TEST(VdbIo, EditedMetadataFailsTheChecksum) {
  const fs::path dir = TempDir("edited");
  const fs::path path = dir / "model.vdb";
  const GridSpec spec = TestSpec();
  WriteVdb(path.string(), spec, TestGrids(spec), {});
  std::vector<char> bytes = ReadBytes(path);
  const std::string text(bytes.begin(), bytes.end());
  const size_t at = text.find("13 7 5");
  ASSERT_NE(at, std::string::npos);
  bytes[at] = '9';  // "93 7 5"
  WriteBytes(path, bytes);
  const std::string error = LoadError(path.string());
  EXPECT_NE(error.find("checksum mismatch"), std::string::npos) << error;
}

TEST(VdbIo, GridsBeyondTheMemoryBudgetAreRefusedBeforeDecoding) {
  const fs::path dir = TempDir("budget");
  const std::string path = (dir / "model.vdb").string();
  const GridSpec spec = TestSpec();  // 455 voxels, 3 grids: 5460 bytes
  WriteVdb(path, spec, TestGrids(spec), {});
  VdbReadOptions options;
  options.max_dense_bytes = 5460;
  EXPECT_NO_THROW(ReadVdb(path, nullptr, nullptr, options));
  options.max_dense_bytes = 5459;
  const std::string error = LoadError(path, options);
  EXPECT_NE(error.find("memory budget"), std::string::npos) << error;
  EXPECT_NE(error.find("13 x 7 x 5"), std::string::npos) << error;

  options = VdbReadOptions();
  options.max_dense_bytes = 0;
  EXPECT_THROW(ReadVdb(path, nullptr, nullptr, options), Error);
}

// A constant grid is stored as a few tiles: 4 M voxels from a file of a few
// kB, far beyond what a samp SDF compresses to.
TEST(VdbIo, GridsFarLargerThanTheFileAreRefused) {
  const fs::path dir = TempDir("expansion");
  const std::string path = (dir / "tiles.vdb").string();
  GridSpec spec;
  spec.dims = Eigen::Vector3i(160, 160, 160);
  DenseGrid grid{"constant", std::vector<float>(size_t(spec.NumVoxels()), 1.0f)};
  WriteVdb(path, spec, {grid}, {});
  ASSERT_LT(fs::file_size(path), 100000u);
  const std::string error = LoadError(path);
  EXPECT_NE(error.find("times its size"), std::string::npos) << error;
  VdbReadOptions options;
  options.max_expansion = 1e6;
  const auto read = ReadVdb(path, nullptr, nullptr, options);
  ASSERT_EQ(read.size(), 1u);
  EXPECT_EQ(read[0].values[12345], 1.0f);
}

TEST(VdbIo, NonRegularFilesAreNotRead) {
  const fs::path dir = TempDir("non_regular");
  EXPECT_NE(LoadError(dir.string()).find("no such file"), std::string::npos);
}

TEST(VdbIo, VdbPrintListsTheFile) {
  const char* vdb_print = "/usr/bin/vdb_print";
  if (!fs::exists(vdb_print)) GTEST_SKIP() << "vdb_print (libopenvdb-tools) is not installed";
  const fs::path dir = TempDir("vdb_print");
  const fs::path path = dir / "model.vdb";
  const GridSpec spec = TestSpec();
  WriteVdb(path.string(), spec, TestGrids(spec), {{"source", "car.obj"}});
  const std::string command = std::string(vdb_print) + " -m '" + path.string() + "' 2>&1";
  FILE* pipe = ::popen(command.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::string output;
  char buffer[512];
  while (std::fgets(buffer, sizeof(buffer), pipe) != nullptr) output += buffer;
  const int status = ::pclose(pipe);
  EXPECT_EQ(status, 0) << output;
  EXPECT_NE(output.find("mean"), std::string::npos) << output;
  EXPECT_NE(output.find("pc_0"), std::string::npos) << output;
  EXPECT_NE(output.find("samp_grid_dims"), std::string::npos) << output;
  EXPECT_NE(output.find("car.obj"), std::string::npos) << output;
}

}  // namespace
}  // namespace samp
