#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>
#include <tuple>

#include "libsamp/core/atomic_file.h"
#include "libsamp/core/error.h"
#include "libsamp/core/grid_spec.h"
#include "libsamp/core/mesh.h"
#include "libsamp/core/object_pool.h"
#include "libsamp/core/ply_io.h"
#include "libsamp/core/progress.h"
#include "tests/testing/expect_error.h"
#include "tests/testing/small_disk.h"

namespace samp {
namespace {

namespace fs = std::filesystem;

fs::path TempDir(const std::string& name) {
  fs::path dir = fs::temp_directory_path() / ("samp_core_test_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

TEST(GridSpec, FromBoxCoversTheBox) {
  const GridSpec grid = GridSpec::FromBox(Eigen::Vector3d(-1, -2, -0.5), Eigen::Vector3d(1, 0, 0.5), 0.1);
  EXPECT_EQ(grid.dims, Eigen::Vector3i(21, 21, 11));
  EXPECT_NEAR(grid.MaxCorner().x(), 1.0, 1e-9);
  EXPECT_EQ(grid.Index(1, 0, 0), 1);
  EXPECT_EQ(grid.Index(0, 1, 0), 21);
  EXPECT_EQ(grid.Index(0, 0, 1), 21 * 21);
  EXPECT_TRUE(grid.Position(10, 20, 5).isApprox(Eigen::Vector3d(0, 0, 0), 1e-12) ||
              grid.Position(10, 20, 5).norm() < 1e-12);
  EXPECT_TRUE(grid.ToVoxel(Eigen::Vector3d(0, 0, 0)).isApprox(Eigen::Vector3d(10, 20, 5)));
}

TEST(GridSpec, CarGrids) {
  // The default is the 6.0 x 2.8 x 2.8 m box, to the bit (models trained before Car() existed).
  const GridSpec literal = GridSpec::FromBox(Eigen::Vector3d(-3.0, -2.3, -1.4), Eigen::Vector3d(3.0, 0.5, 1.4), 0.1);
  const GridSpec car = GridSpec::CarDefault();
  EXPECT_EQ(car.dims, Eigen::Vector3i(61, 29, 29));
  EXPECT_EQ(car.dims, literal.dims);
  for (int a = 0; a < 3; ++a) EXPECT_EQ(car.origin[a], literal.origin[a]) << a;
  EXPECT_EQ(car.voxel_size, literal.voxel_size);
  EXPECT_EQ(car.Size(), Eigen::Vector3d(6.0, 2.8, 2.8));
  // A larger box: centred in x and z, its bottom face 0.5 m below the car.
  const GridSpec big = GridSpec::Car(6.8, 3.1, 3.2, 0.1);
  EXPECT_EQ(big.dims, Eigen::Vector3i(69, 32, 33));
  EXPECT_TRUE(big.MinCorner().isApprox(Eigen::Vector3d(-3.4, -2.6, -1.6), 1e-12));
  EXPECT_TRUE(big.MaxCorner().isApprox(Eigen::Vector3d(3.4, 0.5, 1.6), 1e-12));
  EXPECT_EQ(big.Size(), Eigen::Vector3d(6.8, 3.1, 3.2));
  EXPECT_EQ(GridSpec::Car(big.Size().x(), big.Size().y(), big.Size().z(), 0.1), big);
  // Edges that are no whole number of voxels are rounded outwards (at the top, +x and +z faces).
  const GridSpec coarse = GridSpec::Car(6.0, 2.8, 2.8, 0.15);
  EXPECT_EQ(coarse.dims, Eigen::Vector3i(41, 20, 20));
  EXPECT_EQ(coarse.Size(), Eigen::Vector3d(6.0, 2.85, 2.85));
  test::ExpectError([] { GridSpec::Car(0.0, 2.8, 2.8); }, {"car grid", "must be positive", "0 x 2.8 x 2.8 m"});
  test::ExpectError([] { GridSpec::Car(6.0, -1.0, 2.8); }, {"car grid", "must be positive"});
  test::ExpectError([] { GridSpec::Car(6.0, 2.8, 2.8, 0.0); }, {"voxel_size must be > 0"});
}

TEST(GridSpec, CheckNamesTheField) {
  GridSpec grid;
  grid.voxel_size = -1;
  try {
    grid.Check();
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("voxel_size"), std::string::npos);
  }
  EXPECT_THROW(GridSpec::FromBox(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(-1, 1, 1), 0.1), Error);
}

// Debug builds end the message with the throwing file and line; release
// builds keep the message as written.
TEST(Error, DebugBuildsSayWhere) {
  std::string message;
  const int line = __LINE__ + 2;
  try {
    SAMP_CHECK(1 + 1 == 3) << "arithmetic";
  } catch (const Error& e) {
    message = e.what();
  }
#ifdef NDEBUG
  EXPECT_EQ(message, "arithmetic");
#else
  EXPECT_EQ(message, "arithmetic [core_test.cc:" + std::to_string(line) + "]");
#endif
}

TEST(Mesh, BoxIsClosedAndOutward) {
  const Mesh box = MakeBoxMesh(Eigen::Vector3d(-1, -2, -3), Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(box.triangles.size(), 12u);
  const AlignedBox bounds = box.Bounds();
  EXPECT_TRUE(bounds.Size().isApprox(Eigen::Vector3d(2, 4, 6)));
  // Outward normals: each triangle's normal points away from the centre.
  const auto normals = box.TriangleNormals();
  for (size_t i = 0; i < box.triangles.size(); ++i) {
    const Eigen::Vector3f centroid = (box.vertices[box.triangles[i][0]] + box.vertices[box.triangles[i][1]] +
                                      box.vertices[box.triangles[i][2]]) / 3.f;
    EXPECT_GT(normals[i].dot(centroid), 0.f) << "triangle " << i;
  }
}

TEST(Mesh, SphereIsOutwardAndOnRadius) {
  const Mesh sphere = MakeSphereMesh(Eigen::Vector3d(1, 2, 3), 0.5, 8, 16);
  for (const auto& v : sphere.vertices) {
    EXPECT_NEAR((v.cast<double>() - Eigen::Vector3d(1, 2, 3)).norm(), 0.5, 1e-6);
  }
  const auto normals = sphere.TriangleNormals();
  for (size_t i = 0; i < sphere.triangles.size(); ++i) {
    const Eigen::Vector3f c = sphere.vertices[sphere.triangles[i][0]] - Eigen::Vector3f(1, 2, 3);
    EXPECT_GT(normals[i].dot(c), 0.f);
  }
}

TEST(AtomicFile, FailingWriterLeavesNothing) {
  const fs::path dir = TempDir("atomic");
  const std::string target = (dir / "out.txt").string();
  EXPECT_THROW(WriteFileAtomically(target,
                                   [](const std::string& tmp) {
                                     std::ofstream(tmp) << "half";
                                     SAMP_THROW() << "interrupted";
                                   }),
               Error);
  EXPECT_FALSE(fs::exists(target));
  EXPECT_TRUE(fs::is_empty(dir)) << "temporary file left behind";
  WriteTextFileAtomically(target, "hello");
  std::ifstream in(target);
  std::string content;
  in >> content;
  EXPECT_EQ(content, "hello");
  fs::remove_all(dir);
}

std::string ReadText(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// A full disk: the write fails with the target's name and the OS error, the
// previous file stays byte-identical and no temporary is left behind
// (docs/reliability.md, "Full disks"). Needs root for the small tmpfs.
TEST(AtomicFile, FullDiskLeavesThePreviousFileAndNamesTheError) {
  test::SmallDisk disk("atomic", 64 << 10);
  if (!disk.mounted()) GTEST_SKIP() << disk.reason();
  const std::string target = disk.path() + "/result.txt";
  WriteTextFileAtomically(target, "the good result\n");
  const std::string big(256 << 10, 'x');
  try {
    WriteTextFileAtomically(target, big);
    ADD_FAILURE() << "a 256 KiB write onto a 64 KiB disk did not fail";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(target), std::string::npos) << message;
    EXPECT_NE(message.find(std::strerror(ENOSPC)), std::string::npos) << message;
  }
  EXPECT_EQ(ReadText(target), "the good result\n");
  // A point cloud (binary PLY, built in memory) on the full disk.
  PointCloud cloud;
  for (int i = 0; i < 20000; ++i) cloud.points.emplace_back(float(i), 1.f, 2.f);
  EXPECT_THROW(WritePly(target, cloud), Error);
  EXPECT_EQ(ReadText(target), "the good result\n");
  // Exactly what fits is written; one byte more is refused.
  disk.Fill(8192);
  const size_t free_bytes = disk.FreeBytes();
  EXPECT_THROW(WriteTextFileAtomically(target, std::string(free_bytes + 1, 'y')), Error);
  EXPECT_EQ(ReadText(target), "the good result\n");
  for (const auto& entry : fs::directory_iterator(disk.path())) {
    const std::string name = entry.path().filename().string();
    EXPECT_TRUE(name == "result.txt" || name == "filler") << "left behind: " << name;
  }
}

// WriteBytesChecked names the file and the OS error (here: a folder that does
// not exist, and a device that is always full).
TEST(AtomicFile, CheckedWriteNamesTheFileAndTheOsError) {
  const fs::path dir = TempDir("checked");
  try {
    WriteBytesChecked((dir / "no" / "such" / "x").string(), "abc");
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(std::strerror(ENOENT)), std::string::npos) << e.what();
  }
  if (fs::exists("/dev/full")) {
    try {
      WriteBytesChecked("/dev/full", std::string(100, 'x'), "result.txt");
      ADD_FAILURE() << "writing /dev/full did not fail";
    } catch (const Error& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find("cannot write result.txt"), std::string::npos) << message;
      EXPECT_NE(message.find(std::strerror(ENOSPC)), std::string::npos) << message;
    }
  }
  fs::remove_all(dir);
}

// Symlinks, folders and devices are never replaced by a file.
TEST(AtomicFile, RefusesTargetsThatAreNotRegularFiles) {
  const fs::path dir = TempDir("atomic_targets");
  const fs::path real = dir / "real.txt";
  WriteTextFileAtomically(real.string(), "keep");
  const fs::path link = dir / "link.txt";
  fs::create_symlink(real, link);
  fs::create_directories(dir / "folder.txt");
  for (const fs::path& target : {link, dir / "folder.txt", fs::path("/dev/null")}) {
    try {
      WriteTextFileAtomically(target.string(), "new");
      FAIL() << "expected samp::Error for " << target;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("samp replaces only regular files"), std::string::npos)
          << e.what();
    }
  }
  EXPECT_TRUE(fs::is_symlink(link));
  EXPECT_EQ(ReadText(real), "keep");
  EXPECT_TRUE(fs::is_directory(dir / "folder.txt"));
  fs::remove_all(dir);
}

// A temporary left by a process that no longer runs (kill -9) is removed by
// the next write into that folder; one of a running process is kept.
TEST(AtomicFile, RemovesOrphanTemporariesOfDeadProcesses) {
  const fs::path dir = TempDir("atomic_orphans");
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) ::_exit(0);
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);  // `child` no longer runs
  const fs::path orphan = dir / (".tmp." + std::to_string(child) + ".0.tracks.json");
  const fs::path alive = dir / (".tmp." + std::to_string(::getppid()) + ".3.tracks.json");
  const fs::path unrelated = dir / ".tmp.notes";
  for (const fs::path& p : {orphan, alive, unrelated}) std::ofstream(p) << "x";
  EXPECT_EQ(RemoveOrphanTemporaries(dir.string()), 1);
  EXPECT_FALSE(fs::exists(orphan));
  EXPECT_TRUE(fs::exists(alive));
  EXPECT_TRUE(fs::exists(unrelated));
  fs::remove_all(dir);
}

// SIGTERM while a writer runs: the temporary goes, the target stays as it
// was, and the process still ends by the signal.
TEST(AtomicFile, SignalRemovesTheTemporaryOfARunningWriter) {
  const fs::path dir = TempDir("atomic_signal");
  const fs::path target = dir / "model.vdb";
  WriteTextFileAtomically(target.string(), "old");
  int ready[2];
  ASSERT_EQ(::pipe(ready), 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    RemoveTemporariesOnSignal();
    WriteFileAtomically(target.string(), [&](const std::string& temporary) {
      std::ofstream(temporary) << "half";
      const char byte = 1;
      if (::write(ready[1], &byte, 1) != 1) ::_exit(3);
      for (;;) ::pause();
    });
    ::_exit(4);
  }
  char byte = 0;
  ASSERT_EQ(::read(ready[0], &byte, 1), 1);
  ASSERT_EQ(::kill(child, SIGTERM), 0);
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGTERM) << status;
  int files = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    EXPECT_EQ(entry.path().filename().string(), "model.vdb") << "left behind: " << entry.path().string();
    ++files;
  }
  EXPECT_EQ(files, 1);
  EXPECT_EQ(ReadText(target), "old");
  ::close(ready[0]);
  ::close(ready[1]);
  fs::remove_all(dir);
}

// Every path under `folder`, relative, sorted.
std::vector<std::string> Listing(const fs::path& folder) {
  std::vector<std::string> paths;
  for (const auto& entry : fs::recursive_directory_iterator(folder))
    paths.push_back(entry.path().lexically_relative(folder).string());
  std::sort(paths.begin(), paths.end());
  return paths;
}

// A staged folder replaces the previous one as a whole on Commit(); without
// Commit() the previous one stays; nothing temporary is left either way.
TEST(StagedFolder, CommitReplacesThePreviousFolderAsAWhole) {
  const fs::path dir = TempDir("staged_commit");
  const fs::path target = dir / "out";
  {
    StagedFolder first(target.string());
    EXPECT_EQ(fs::path(first.path()).filename(), "out");
    EXPECT_FALSE(fs::exists(target));
    WriteTextFileAtomically(first.path() + "/old.txt", "old");
    WriteTextFileAtomically(first.path() + "/meshes/track_1.ply", "old");
    first.Commit();
    EXPECT_FALSE(first.replaced());
  }
  EXPECT_EQ(Listing(target), (std::vector<std::string>{".samp_run", "meshes", "meshes/track_1.ply", "old.txt"}));
  {
    StagedFolder abandoned(target.string() + "/");  // a trailing slash names the same folder
    WriteTextFileAtomically(abandoned.path() + "/new.txt", "new");
  }
  EXPECT_EQ(Listing(target), (std::vector<std::string>{".samp_run", "meshes", "meshes/track_1.ply", "old.txt"}));
  {
    StagedFolder second(target.string());
    WriteTextFileAtomically(second.path() + "/new.txt", "new");
    second.Commit();
    EXPECT_TRUE(second.replaced());
  }
  EXPECT_EQ(Listing(target), (std::vector<std::string>{".samp_run", "new.txt"}));
  EXPECT_EQ(ReadText(target / "new.txt"), "new");
  // The marker: samp's, with the run id and every file of the run.
  const std::string marker = ReadText(target / kOutputFolderMarker);
  EXPECT_EQ(marker.rfind("samp output folder\nrun_id ", 0), 0u) << marker;
  EXPECT_NE(marker.find("\nfile new.txt\n"), std::string::npos) << marker;
  EXPECT_TRUE(CheckReplaceableOutputFolder(target.string()));
  EXPECT_EQ(Listing(dir), (std::vector<std::string>{"out", "out/.samp_run", "out/new.txt"}));
  // A symbolic link to a folder: the folder is replaced, the link stays.
  const fs::path link = dir / "link";
  fs::create_directory_symlink(target, link);
  {
    StagedFolder third(link.string());
    EXPECT_EQ(fs::path(third.target()), fs::canonical(target));
    WriteTextFileAtomically(third.path() + "/third.txt", "third");
    third.Commit();
  }
  EXPECT_TRUE(fs::is_symlink(link));
  EXPECT_EQ(Listing(link.string() + "/"), (std::vector<std::string>{".samp_run", "third.txt"}));
  fs::remove_all(dir);
}

// Output folder names of 241-255 bytes (the longest a file system allows):
// the temporaries beside them are cut to 255 bytes and keep the extension.
TEST(StagedFolder, LongNamesUpToTheFileSystemLimitWork) {
  const fs::path dir = TempDir("staged_long");
  for (size_t length : {241u, 250u, 255u}) {
    const std::string name(length, 'n');
    StagedFolder staged((dir / name).string());
    WriteTextFileAtomically(staged.path() + "/tracks.json", "{}");
    staged.Commit();
    EXPECT_EQ(ReadText(dir / name / "tracks.json"), "{}") << length;
    const std::string file = std::string(length - 4, 'f') + ".txt";
    WriteTextFileAtomically((dir / file).string(), "x");
    EXPECT_EQ(ReadText(dir / file), "x") << length;
    std::string seen;
    WriteFileAtomically((dir / file).string(), [&](const std::string& temporary) {
      seen = fs::path(temporary).filename().string();
      WriteBytesChecked(temporary, "y");
    });
    EXPECT_LE(seen.size(), 255u);
    EXPECT_EQ(fs::path(seen).extension(), ".txt") << seen;
  }
  fs::remove_all(dir);
}

// Which folders a run may replace: new, empty, or made by samp with nothing
// else in them (the foreign files are listed).
TEST(StagedFolder, ReplacesOnlyFoldersItCanProveItMade) {
  const fs::path dir = TempDir("staged_proof");
  EXPECT_FALSE(CheckReplaceableOutputFolder((dir / "new").string()));
  fs::create_directories(dir / "empty");
  EXPECT_FALSE(CheckReplaceableOutputFolder((dir / "empty").string()));
  WriteTextFileAtomically((dir / "user" / "tracks.json").string(), "{}");
  WriteTextFileAtomically((dir / "user" / "config.json").string(), "{}");
  WriteTextFileAtomically((dir / "user" / "thesis.tex").string(), "t");
  EXPECT_THROW(CheckReplaceableOutputFolder((dir / "user").string()), Error);
  {
    StagedFolder run((dir / "run").string());
    WriteTextFileAtomically(run.path() + "/a/b.txt", "b");
    run.Commit();
    EXPECT_EQ(run.run_id().size(), 32u);
  }
  EXPECT_TRUE(CheckReplaceableOutputFolder((dir / "run").string()));
  WriteTextFileAtomically((dir / "run" / "a" / "mine.txt").string(), "m");
  WriteTextFileAtomically((dir / "run" / "notes.txt").string(), "n");
  try {
    CheckReplaceableOutputFolder((dir / "run").string());
    ADD_FAILURE() << "foreign files accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("holds 2 file(s) samp did not write: a/mine.txt, notes.txt"),
              std::string::npos)
        << e.what();
  }
  // Recorded by samp (as `samp view` records its page): accepted again.
  RecordInOutputFolder((dir / "run").string(), {(dir / "run" / "a" / "mine.txt").string(),
                                                (dir / "run" / "notes.txt").string()});
  EXPECT_TRUE(CheckReplaceableOutputFolder((dir / "run").string()));
  // Inputs by path and by inode.
  EXPECT_TRUE(IsInsideFolder((dir / "run" / "a" / "b.txt").string(), (dir / "run").string()));
  EXPECT_FALSE(IsInsideFolder((dir / "user" / "thesis.tex").string(), (dir / "run").string()));
  fs::create_directory_symlink(dir / "run", dir / "alias");
  EXPECT_TRUE(IsInsideFolder((dir / "alias" / "a" / "b.txt").string(), (dir / "run").string()));
  fs::create_hard_link(dir / "user" / "thesis.tex", dir / "hard.tex");
  EXPECT_TRUE(SameFile((dir / "hard.tex").string(), (dir / "user" / "thesis.tex").string()));
  EXPECT_FALSE(SameFile((dir / "hard.tex").string(), (dir / "run" / "notes.txt").string()));
  fs::remove_all(dir);
}

TEST(StagedFolder, RefusesTargetsThatAreNotFolders) {
  const fs::path dir = TempDir("staged_refuse");
  WriteTextFileAtomically((dir / "file").string(), "keep");
  fs::create_symlink(dir / "nowhere", dir / "dangling");
  fs::create_symlink(dir / "file", dir / "file_link");
  for (const std::string name : {"file", "dangling", "file_link"}) {
    try {
      StagedFolder staged((dir / name).string());
      ADD_FAILURE() << name << " accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find((dir / name).string()), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(StagedFolder("/"), Error);
  EXPECT_EQ(ReadText(dir / "file"), "keep");
  EXPECT_EQ(Listing(dir), (std::vector<std::string>{"dangling", "file", "file_link"}));
  fs::remove_all(dir);
}

// A folder left by a process that no longer runs is removed with its
// contents; one of a running process, and a plain folder, are kept.
TEST(StagedFolder, OrphanFoldersOfDeadProcessesAreRemoved) {
  const fs::path dir = TempDir("staged_orphans");
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) ::_exit(0);
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  const fs::path orphan = dir / (".tmp." + std::to_string(child) + ".4.out");
  const fs::path alive = dir / (".tmp." + std::to_string(::getppid()) + ".4.out");
  for (const fs::path& p : {orphan / "out/label_02", alive / "out", dir / "out"}) fs::create_directories(p);
  std::ofstream(orphan / "out/label_02/0001.txt") << "x";
  EXPECT_EQ(RemoveOrphanTemporaries(dir.string()), 1);
  EXPECT_FALSE(fs::exists(orphan));
  EXPECT_TRUE(fs::exists(alive));
  EXPECT_TRUE(fs::exists(dir / "out"));
  fs::remove_all(dir);
}

// SIGINT while a staged folder is being filled (files in subfolders, one
// atomic write still open): the temporary folder goes, the previous folder
// stays as it was, and the process still ends by the signal.
TEST(StagedFolder, SignalRemovesTheTemporaryFolder) {
  const fs::path dir = TempDir("staged_signal");
  const fs::path target = dir / "out";
  WriteTextFileAtomically((target / "tracks.json").string(), "old");
  int ready[2];
  ASSERT_EQ(::pipe(ready), 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    RemoveTemporariesOnSignal();
    StagedFolder staged(target.string());
    for (int i = 0; i < 50; ++i) {
      WriteTextFileAtomically(staged.path() + "/meshes/" + std::to_string(i) + "/track.ply", "half");
    }
    WriteFileAtomically(staged.path() + "/tracks.json", [&](const std::string& temporary) {
      std::ofstream(temporary) << "half";
      const char byte = 1;
      if (::write(ready[1], &byte, 1) != 1) ::_exit(3);
      for (;;) ::pause();
    });
    ::_exit(4);
  }
  char byte = 0;
  ASSERT_EQ(::read(ready[0], &byte, 1), 1);
  ASSERT_EQ(::kill(child, SIGINT), 0);
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGINT) << status;
  EXPECT_EQ(Listing(dir), (std::vector<std::string>{"out", "out/tracks.json"}));
  EXPECT_EQ(ReadText(target / "tracks.json"), "old");
  ::close(ready[0]);
  ::close(ready[1]);
  fs::remove_all(dir);
}

TEST(PlyIo, WritesHeaderAndBinaryBody) {
  const fs::path dir = TempDir("ply");
  const std::string path = (dir / "box.ply").string();
  WritePly(path, MakeBoxMesh(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 1, 1)));
  std::ifstream in(path, std::ios::binary);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "ply");
  // 8 vertices * 12 bytes + 12 faces * 13 bytes after the header.
  std::ifstream whole(path, std::ios::binary);
  const std::string all((std::istreambuf_iterator<char>(whole)), std::istreambuf_iterator<char>());
  const size_t header_end = all.find("end_header\n") + std::string("end_header\n").size();
  EXPECT_EQ(all.size() - header_end, 8u * 12u + 12u * 13u);
  PointCloud cloud;
  cloud.points.emplace_back(0, 0, 0);
  cloud.colors.push_back({1, 2, 3});
  cloud.colors.push_back({1, 2, 3});
  EXPECT_THROW(WritePly((dir / "bad.ply").string(), cloud), Error);
  fs::remove_all(dir);
}

TEST(PlyIo, PointCloudRoundTripsWithAndWithoutColours) {
  const fs::path dir = TempDir("ply_points");
  PointCloud cloud;
  for (int i = 0; i < 50; ++i) {
    // 10/256 as x puts a newline byte first: the writer swaps a safe point to the front.
    cloud.points.emplace_back(i == 0 ? 10.0f / 256.0f : 0.5f * i, -1.25f * i, 3.0f);
    cloud.colors.push_back({uint8_t(i), 64, uint8_t(255 - i)});
  }
  WritePly((dir / "c.ply").string(), cloud);
  const PointCloud read = ReadPointCloudPly((dir / "c.ply").string());
  ASSERT_EQ(read.points.size(), cloud.points.size());
  ASSERT_EQ(read.colors.size(), cloud.colors.size());
  // The writer may reorder points (SafeFirstVertex): compare as sets of (point, colour).
  auto key = [](const Eigen::Vector3f& p, const Eigen::Matrix<uint8_t, 3, 1>& c) {
    return std::make_tuple(p.x(), p.y(), p.z(), int(c[0]), int(c[1]), int(c[2]));
  };
  std::vector<std::tuple<float, float, float, int, int, int>> a, b;
  for (size_t i = 0; i < cloud.points.size(); ++i) a.push_back(key(cloud.points[i], cloud.colors[i]));
  for (size_t i = 0; i < read.points.size(); ++i) b.push_back(key(read.points[i], read.colors[i]));
  std::sort(a.begin(), a.end());
  std::sort(b.begin(), b.end());
  EXPECT_EQ(a, b);
  cloud.colors.clear();
  WritePly((dir / "p.ply").string(), cloud);
  EXPECT_EQ(ReadPointCloudPly((dir / "p.ply").string()).points.size(), 50u);
  EXPECT_TRUE(ReadPointCloudPly((dir / "p.ply").string()).colors.empty());
  // A mesh file is not a point cloud; a truncated file is named.
  WritePly((dir / "m.ply").string(), MakeBoxMesh(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 1, 1)));
  EXPECT_THROW(ReadPointCloudPly((dir / "m.ply").string()), Error);
  std::string bytes;
  {
    std::ifstream in((dir / "c.ply").string(), std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  {
    std::ofstream out((dir / "t.ply").string(), std::ios::binary);
    out << bytes.substr(0, bytes.size() - 7);
  }
  try {
    ReadPointCloudPly((dir / "t.ply").string());
    ADD_FAILURE() << "no error for a truncated file";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ReadPointCloudPly((dir / "missing.ply").string()), Error);
  fs::remove_all(dir);
}

TEST(Progress, FormatsDurations) {
  EXPECT_EQ(Progress::FormatDuration(12.34), "12.3s");
  EXPECT_EQ(Progress::FormatDuration(185), "3m05s");
  EXPECT_EQ(Progress::FormatDuration(3720), "1h02m");
}

TEST(ObjectPool, ReusesObjectsAndGivesConcurrentLeasesTheirOwn) {
  ObjectPool<std::vector<int>> pool;
  const std::vector<int>* first = nullptr;
  {
    ObjectPool<std::vector<int>>::Lease lease(&pool);
    first = lease.get();
    lease->assign(1000, 7);  // buffers a later lease finds again
    ObjectPool<std::vector<int>>::Lease second(&pool);
    EXPECT_NE(second.get(), first);  // two leases at once: two objects
    EXPECT_TRUE(second->empty());
  }
  EXPECT_EQ(pool.NumFree(), 2u);
  {
    ObjectPool<std::vector<int>>::Lease again(&pool);
    ObjectPool<std::vector<int>>::Lease other(&pool);
    ASSERT_TRUE(again.get() == first || other.get() == first);
    const std::vector<int>& reused = again.get() == first ? *again : *other;
    EXPECT_EQ(reused.size(), 1000u);
  }
  // Many threads: every lease is exclusive while it lasts.
  std::vector<std::thread> threads;
  std::atomic<int> clashes{0};
  for (int t = 0; t < 8; ++t) {
    threads.emplace_back([&pool, &clashes, t] {
      for (int round = 0; round < 200; ++round) {
        ObjectPool<std::vector<int>>::Lease lease(&pool);
        lease->assign(16, t);
        std::this_thread::yield();
        for (const int value : *lease) clashes += int(value != t);
      }
    });
  }
  for (std::thread& thread : threads) thread.join();
  EXPECT_EQ(clashes.load(), 0);
  EXPECT_GE(pool.NumFree(), 2u);
  EXPECT_LE(pool.NumFree(), 10u);
}

}  // namespace
}  // namespace samp
