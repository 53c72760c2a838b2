// Atomic output: write to a temporary file (or folder) beside the target, then
// rename. An interrupted or failing writer never leaves a half-written target
// behind.
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

// Removes `.tmp.<pid>.<n>.*` files and folders (StagedFolder) in `folder`
// whose process no longer runs; returns how many were removed. Called by
// WriteFileAtomically and StagedFolder once per folder.
int RemoveOrphanTemporaries(const std::string& folder);

// A folder written completely or not at all. The writer fills path(), a fresh
// folder of the target's name inside a temporary folder `.tmp.<pid>.<n>.<name>`
// beside the target; Commit() puts it in place of the target: a previous
// folder of that name is swapped out in one step (Linux renameat2
// RENAME_EXCHANGE; where the file system lacks it, two renames, between which
// the target is briefly absent) and then removed with everything in it.
// Without Commit() (an exception, a failed run) the destructor removes the
// temporary folder and the target stays as it was. The temporary folder is
// registered for RemoveTemporariesOnSignal (removed on SIGINT/SIGTERM/SIGHUP)
// and one left by a kill -9 is removed by the next StagedFolder or atomic write
// beside it (RemoveOrphanTemporaries). A target that is a symbolic link to a
// folder is resolved (the link stays and shows the new folder); a target that
// exists and is not a folder (a file, a device, a dangling link) is refused
// with samp::Error, so is one without a parent (`/`). Which folders may be
// replaced is the caller's decision (see pipeline/run_fit.h). Not thread-safe
// for one instance; distinct instances are independent.
class StagedFolder {
 public:
  explicit StagedFolder(const std::string& target);
  ~StagedFolder();
  StagedFolder(const StagedFolder&) = delete;
  StagedFolder& operator=(const StagedFolder&) = delete;

  // Where to write: <parent of target>/.tmp.<pid>.<n>.<name>/<name>.
  const std::string& path() const { return path_; }
  // The folder Commit() replaces (the resolved target).
  const std::string& target() const { return target_; }
  // True when Commit() replaced an existing folder.
  bool replaced() const { return replaced_; }
  // Moves path() to target(); throws samp::Error when the rename fails (the
  // target then stays as it was). A failure to remove the previous folder
  // afterwards is a warning (the next run removes it).
  void Commit();

 private:
  std::string target_, temporary_, path_;
  int slot_ = -1;
  bool committed_ = false, replaced_ = false;
};

}  // namespace samp
