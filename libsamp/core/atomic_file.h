// Atomic output: write to a temporary file (or folder) beside the target, then
// rename. An interrupted or failing writer never leaves a half-written target
// behind.
#pragma once

#include <functional>
#include <string>
#include <vector>

namespace samp {

// Calls `writer(temporary_path)`, which must create that file; then flushes
// it to the disk (fsync, whose error, e.g. ENOSPC or EIO, is an error) and on
// success renames it onto `path` (atomic on POSIX within one file system). If
// the writer or the flush fails, the temporary file is removed, `path` stays
// as it was (byte-identical) and the exception (samp::Error naming `path` and
// the OS error) propagates. Writers that produce their bytes in memory should
// use WriteBytesAtomically, which checks every write() itself.
// Creates missing parent directories of `path`. Refuses (samp::Error) a
// target that exists and is not a regular file (a symlink, device, folder):
// samp never replaces one by a file. Temporaries are named
// `.tmp.<pid>.<n>.<file name>`; the first write into a folder removes the
// ones left there by processes that no longer run (a kill -9), and while a
// writer runs its temporary is registered for RemoveTemporariesOnSignal.
// Thread-safe.
void WriteFileAtomically(const std::string& path,
                         const std::function<void(const std::string& temporary_path)>& writer);

// Atomically writes `bytes` to `path`: every write() is checked (short writes
// continued, EINTR retried), then fsync() and close(); any error (ENOSPC, EIO,
// EDQUOT, ...) throws samp::Error "cannot write PATH: <OS error>" and leaves
// `path` as it was. `verify(temporary_path)`, when given, runs on the written
// temporary before the rename (e.g. re-read it); if it throws, `path` stays.
void WriteBytesAtomically(const std::string& path, const std::string& bytes,
                          const std::function<void(const std::string& temporary_path)>& verify = nullptr);

// Convenience: atomically writes `contents` to `path` (WriteBytesAtomically).
void WriteTextFileAtomically(const std::string& path, const std::string& contents);

// Writes `bytes` to `path` (created or truncated; not atomic): every write()
// checked, then fsync() and close(). Throws samp::Error "cannot write NAME:
// <OS error>" where NAME is `name_for_errors` (the final target) or `path`.
void WriteBytesChecked(const std::string& path, const std::string& bytes,
                       const std::string& name_for_errors = "");

// Installs SIGINT / SIGTERM / SIGHUP handlers that remove the temporaries of
// writers still running, then end the process with the signal's default
// action (the exit status still says which signal). For executables' main;
// idempotent.
void RemoveTemporariesOnSignal();

// Removes `.tmp.<pid>.<n>.*` files and folders (StagedFolder) in `folder`
// whose process no longer runs; returns how many were removed. Called by
// WriteFileAtomically and StagedFolder once per folder.
int RemoveOrphanTemporaries(const std::string& folder);

// The marker file StagedFolder::Commit writes into every output folder:
// "samp output folder", the run id and one line "file <relative path>" per
// file it wrote (the marker itself excluded).
inline constexpr char kOutputFolderMarker[] = ".samp_run";

// What may be replaced as a whole: a folder that does not exist, an empty
// folder, or one samp can prove it made (CheckReplaceableOutputFolder: its
// marker file lists every file in it). Returns true when `folder` exists
// and is not empty (an earlier run, to be replaced). Throws samp::Error when
// `folder` exists and is not a folder, has no valid marker ("not made by
// samp"), or holds files the marker does not list (listing up to 20 of these
// foreign files, which samp would otherwise delete). `why` is appended to the
// message (what the caller does with the folder).
bool CheckReplaceableOutputFolder(const std::string& folder, const std::string& why = "");

// Adds `files` (paths of files samp has just written into `folder`, e.g.
// `samp view` writing OUT/index.html) to the marker of `folder`, so that a
// later run may still replace it. Does nothing when `folder` has no valid
// marker (it is not samp's) or a file lies outside it. The marker is
// rewritten atomically.
void RecordInOutputFolder(const std::string& folder, const std::vector<std::string>& files);

// True when `a` and `b` name the same file or folder (same device and inode,
// after following symbolic links); false when either does not exist.
bool SameFile(const std::string& a, const std::string& b);

// True when `path` is `folder` or lies inside it, by resolved path or by the
// device and inode of `path` and each of its parent folders (so a bind mount,
// a hard link to the folder or a symbolic link does not hide it).
bool IsInsideFolder(const std::string& path, const std::string& folder);

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
  // Writes the marker file (kOutputFolderMarker: a random run id and every
  // file of path(), so that a later run can prove the folder is samp's), then
  // moves path() to target(); throws samp::Error when a write or the rename
  // fails (the target then stays as it was). A failure to remove the previous
  // folder afterwards is a warning (the next run removes it).
  void Commit();
  // The run id written into the marker (32 hex digits from std::random_device).
  const std::string& run_id() const { return run_id_; }

 private:
  std::string target_, temporary_, path_, run_id_;
  int slot_ = -1;
  bool committed_ = false, replaced_ = false;
};

}  // namespace samp
