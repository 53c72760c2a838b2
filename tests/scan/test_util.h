// Helpers shared by the scan tests: private temporary folders.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace samp {
namespace test {

// A fresh, empty folder under the system temp dir, unique per process and name.
inline std::filesystem::path TempDir(const std::string& name) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("samp_scan_test_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

inline void WriteText(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

}  // namespace test
}  // namespace samp
