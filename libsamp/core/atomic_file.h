// Atomic output: write to a temporary file beside the target, then rename.
// An interrupted or failing writer never leaves a half-written target behind.
#pragma once

#include <functional>
#include <string>

namespace samp {

// Calls `writer(temporary_path)`, which must create that file; on success
// renames it onto `path` (atomic on POSIX within one file system). If the
// writer throws, the temporary file is removed and the exception propagates.
// Creates missing parent directories of `path`.
void WriteFileAtomically(const std::string& path,
                         const std::function<void(const std::string& temporary_path)>& writer);

// Convenience: atomically writes `contents` to `path`.
void WriteTextFileAtomically(const std::string& path, const std::string& contents);

}  // namespace samp
