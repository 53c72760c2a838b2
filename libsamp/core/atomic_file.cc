#include "libsamp/core/atomic_file.h"

#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>

#include "libsamp/core/error.h"

namespace samp {

void WriteFileAtomically(const std::string& path,
                         const std::function<void(const std::string&)>& writer) {
  namespace fs = std::filesystem;
  static std::atomic<int> counter{0};
  const fs::path target(path);
  if (target.has_parent_path()) {
    std::error_code ec;
    fs::create_directories(target.parent_path(), ec);
    SAMP_CHECK(!ec) << "cannot create directory " << target.parent_path().string() << ": "
                    << ec.message();
  }
  // The temporary keeps the target's extension: some writers pick the format from it.
  const std::string temporary =
      (target.parent_path() / (".tmp." + std::to_string(::getpid()) + "." +
                               std::to_string(counter++) + "." + target.filename().string()))
          .string();
  try {
    writer(temporary);
    SAMP_CHECK(fs::exists(temporary)) << "writer did not create " << temporary;
    std::error_code ec;
    fs::rename(temporary, target, ec);
    SAMP_CHECK(!ec) << "cannot rename " << temporary << " to " << path << ": " << ec.message();
  } catch (...) {
    std::error_code ignored;
    fs::remove(temporary, ignored);
    throw;
  }
}

void WriteTextFileAtomically(const std::string& path, const std::string& contents) {
  WriteFileAtomically(path, [&](const std::string& temporary) {
    std::ofstream out(temporary, std::ios::binary);
    SAMP_CHECK(out) << "cannot open " << temporary << " for writing";
    out << contents;
    out.close();
    SAMP_CHECK(out) << "error writing " << temporary;
  });
}

}  // namespace samp
