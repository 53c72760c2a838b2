// A small, full-able file system for disk-full tests: a tmpfs of a given size
// mounted on a fresh folder under the temporary directory, unmounted and
// removed again by the destructor. Mounting needs root (CAP_SYS_ADMIN); where
// it is not possible, mounted() is false and reason() says why, for
// GTEST_SKIP(). Tests use it as
//   test::SmallDisk disk("name", 64 << 10);
//   if (!disk.mounted()) GTEST_SKIP() << disk.reason();
#pragma once

#include <sys/mount.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

namespace samp::test {

class SmallDisk {
 public:
  SmallDisk(const std::string& name, size_t bytes) {
    namespace fs = std::filesystem;
    path_ = (fs::temp_directory_path() / ("samp_small_disk_" + name + "_" + std::to_string(::getpid()))).string();
    std::error_code ec;
    fs::create_directories(path_, ec);
    if (ec) {
      reason_ = "cannot create " + path_ + ": " + ec.message();
      return;
    }
    if (::geteuid() != 0) {
      reason_ = "disk-full test skipped: mounting a small tmpfs needs root (the CI runs as root)";
      return;
    }
    const std::string options = "size=" + std::to_string(bytes) + ",mode=0700";
    if (::mount("tmpfs", path_.c_str(), "tmpfs", MS_NOSUID | MS_NODEV, options.c_str()) != 0) {
      reason_ = "disk-full test skipped: cannot mount a tmpfs on " + path_ + ": " + std::strerror(errno);
      return;
    }
    mounted_ = true;
  }
  ~SmallDisk() {
    if (mounted_ && ::umount2(path_.c_str(), 0) != 0) ::umount2(path_.c_str(), MNT_DETACH);
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  SmallDisk(const SmallDisk&) = delete;
  SmallDisk& operator=(const SmallDisk&) = delete;

  bool mounted() const { return mounted_; }
  const std::string& reason() const { return reason_; }
  const std::string& path() const { return path_; }

  // Fills the disk up to `leave_bytes` free bytes with a file "filler".
  void Fill(size_t leave_bytes) const {
    std::ofstream filler(path_ + "/filler", std::ios::binary);
    const std::string block(4096, 'x');
    while (FreeBytes() > leave_bytes + block.size() && filler.write(block.data(), std::streamsize(block.size()))) {
      filler.flush();
    }
  }
  size_t FreeBytes() const {
    std::error_code ec;
    const auto space = std::filesystem::space(path_, ec);
    return ec ? 0 : size_t(space.available);
  }

 private:
  std::string path_, reason_;
  bool mounted_ = false;
};

}  // namespace samp::test
