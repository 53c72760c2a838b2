// Atomic output: write to a temporary file beside the target, then rename.
// An interrupted or failing writer never leaves a half-written target behind.
#pragma once

#include <functional>
#include <string>

namespace samp {

// Calls `writer(temporary_path)`, which must create that file; on success
// renames it onto `path` (atomic on POSIX within one file system). If the
// writer throws, the temporary file is removed and the exception propagates.
// Creates missing parent directories of `path`. Refuses (samp::Error) a
// target that exists and is not a regular file (a symlink, device, folder):
// samp never replaces one by a file. Temporaries are named
// `.tmp.<pid>.<n>.<file name>`; the first write into a folder removes the
// ones left there by processes that no longer run (a kill -9), and while a
// writer runs its temporary is registered for RemoveTemporariesOnSignal.
// Thread-safe.
void WriteFileAtomically(const std::string& path,
                         const std::function<void(const std::string& temporary_path)>& writer);

// Convenience: atomically writes `contents` to `path`.
void WriteTextFileAtomically(const std::string& path, const std::string& contents);

// Installs SIGINT / SIGTERM / SIGHUP handlers that remove the temporaries of
// writers still running, then end the process with the signal's default
// action (the exit status still says which signal). For executables' main;
// idempotent.
void RemoveTemporariesOnSignal();

// Removes `.tmp.<pid>.<n>.*` files in `folder` whose process no longer runs;
// returns how many were removed. Called by WriteFileAtomically once per folder.
int RemoveOrphanTemporaries(const std::string& folder);

}  // namespace samp
