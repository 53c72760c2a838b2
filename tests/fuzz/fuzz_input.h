// Shared by the fuzz targets: every samp reader takes a path, so a target
// writes the fuzzer's bytes to a file of its own in a private temporary
// folder (one per process, removed at exit) and calls the reader on it.
// A target passes when the reader returns or throws samp::Error; any other
// exception escapes LLVMFuzzerTestOneInput and ends the run as a finding,
// like a crash or a sanitizer report.
#pragma once

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

namespace samp::fuzz {

class FuzzFolder {
 public:
  FuzzFolder()
      : dir_(std::filesystem::temp_directory_path() /
             ("samp_fuzz_" + std::to_string(::getpid()))) {
    std::filesystem::create_directories(dir_);
  }
  ~FuzzFolder() {
    std::error_code ignored;
    std::filesystem::remove_all(dir_, ignored);
  }
  // Writes `size` bytes to `name` in the folder and returns its path.
  std::string Write(const std::string& name, const uint8_t* data, size_t size) const {
    const std::filesystem::path path = dir_ / name;
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
    return path.string();
  }
  const std::filesystem::path& dir() const { return dir_; }

 private:
  std::filesystem::path dir_;
};

inline const FuzzFolder& Folder() {
  static const FuzzFolder folder;
  return folder;
}

}  // namespace samp::fuzz
