#include "libsamp/core/atomic_file.h"

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <mutex>
#include <random>
#include <sstream>
#include <sys/stat.h>
#include <vector>
#include <set>

#include "libsamp/core/error.h"
#include "libsamp/core/log.h"

namespace samp {
namespace {

namespace fs = std::filesystem;

// Temporaries of running writers, readable from a signal handler: fixed slots
// of NUL-terminated paths, a slot in use while `busy` is set.
constexpr int kMaxLiveTemporaries = 64;
constexpr size_t kMaxTemporaryPath = 4096;
struct TemporarySlot {
  std::atomic<bool> busy{false};
  std::atomic<bool> ready{false};
  std::atomic<bool> folder{false};  // a StagedFolder's temporary folder: removed with its contents
  char path[kMaxTemporaryPath];
};
std::array<TemporarySlot, kMaxLiveTemporaries> g_temporaries;

// Names of temporaries: `.tmp.<pid>.<n>.<name>`, n from this counter.
std::atomic<int> g_counter{0};

// Registers `path` for removal on a signal; -1 when every slot is taken (the
// file is then removed only by the writer or by the next run).
int RegisterTemporary(const std::string& path, bool folder = false) {
  if (path.size() + 1 > kMaxTemporaryPath) return -1;
  for (int i = 0; i < kMaxLiveTemporaries; ++i) {
    bool expected = false;
    if (g_temporaries[i].busy.compare_exchange_strong(expected, true)) {
      std::memcpy(g_temporaries[i].path, path.c_str(), path.size() + 1);
      g_temporaries[i].folder.store(folder);
      g_temporaries[i].ready.store(true);
      return i;
    }
  }
  return -1;
}

void UnregisterTemporary(int slot) {
  if (slot < 0) return;
  g_temporaries[slot].ready.store(false);
  g_temporaries[slot].busy.store(false);
}

// Removes what the folder `dir_fd` holds, with async-signal-safe calls only
// (getdents64, unlinkat, openat, close: no allocation). Best effort: another
// thread may still be writing into the folder; what stays is an orphan that
// the next run removes.
void RemoveFolderContentsSignalSafe(int dir_fd, int depth) {
  constexpr int kMaxDepth = 16;
  if (depth > kMaxDepth) return;
  alignas(8) char buffer[2048];
  for (int pass = 0; pass < 4; ++pass) {
    if (::lseek(dir_fd, 0, SEEK_SET) != 0) return;
    bool found = false;
    for (;;) {
      const ssize_t n = ::getdents64(dir_fd, buffer, sizeof(buffer));
      if (n <= 0) break;
      for (ssize_t offset = 0; offset < n;) {
        const auto* entry = reinterpret_cast<const struct dirent64*>(buffer + offset);
        offset += entry->d_reclen;
        const char* name = entry->d_name;
        if (name[0] == '.' && (name[1] == '\0' || (name[1] == '.' && name[2] == '\0'))) continue;
        found = true;
        if (::unlinkat(dir_fd, name, 0) == 0) continue;
        const int child = ::openat(dir_fd, name, O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
        if (child < 0) continue;
        RemoveFolderContentsSignalSafe(child, depth + 1);
        ::close(child);
        ::unlinkat(dir_fd, name, AT_REMOVEDIR);
      }
    }
    if (!found) return;
  }
}

void RemoveFolderSignalSafe(const char* path) {
  const int fd = ::open(path, O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
  if (fd < 0) return;
  RemoveFolderContentsSignalSafe(fd, 0);
  ::close(fd);
  ::rmdir(path);
}

extern "C" void RemoveTemporariesAndReraise(int signal_number) {
  const int saved_errno = errno;
  for (auto& slot : g_temporaries) {
    if (!slot.ready.load()) continue;
    if (slot.folder.load()) {
      RemoveFolderSignalSafe(slot.path);
    } else {
      ::unlink(slot.path);  // async-signal-safe
    }
  }
  errno = saved_errno;
  ::signal(signal_number, SIG_DFL);
  ::raise(signal_number);
}

// "<prefix>.tmp.<pid>.<n>.<name>": the pid, or -1 when `name` is not a temporary.
long TemporaryPid(const std::string& name) {
  if (name.rfind(".tmp.", 0) != 0) return -1;
  size_t pos = 5;
  long pid = 0;
  int digits = 0;
  while (pos < name.size() && name[pos] >= '0' && name[pos] <= '9' && digits < 10) {
    pid = pid * 10 + (name[pos] - '0');
    ++pos;
    ++digits;
  }
  if (digits == 0 || pos >= name.size() || name[pos] != '.') return -1;
  ++pos;
  int counter_digits = 0;
  while (pos < name.size() && name[pos] >= '0' && name[pos] <= '9') {
    ++pos;
    ++counter_digits;
  }
  if (counter_digits == 0 || pos + 1 >= name.size() || name[pos] != '.') return -1;
  return pid;
}

bool ProcessRuns(long pid) {
  if (pid <= 0) return false;
  if (pid == long(::getpid())) return true;
  return ::kill(pid_t(pid), 0) == 0 || errno == EPERM;
}

const char* KindOf(const fs::file_status& status) {
  switch (status.type()) {
    case fs::file_type::regular: return "a file";
    case fs::file_type::symlink: return "a symbolic link";
    case fs::file_type::directory: return "a folder";
    case fs::file_type::block:
    case fs::file_type::character: return "a device";
    case fs::file_type::fifo: return "a pipe";
    case fs::file_type::socket: return "a socket";
    default: return "not a regular file";
  }
}

}  // namespace

int RemoveOrphanTemporaries(const std::string& folder) {
  std::error_code ec;
  int removed = 0;
  fs::directory_iterator it(folder.empty() ? fs::path(".") : fs::path(folder), ec);
  if (ec) return 0;
  for (const fs::directory_entry& entry : it) {
    const std::string name = entry.path().filename().string();
    const long pid = TemporaryPid(name);
    if (pid < 0 || ProcessRuns(pid)) continue;
    std::error_code type_ec;
    const fs::file_status status = entry.symlink_status(type_ec);
    if (type_ec) continue;
    if (fs::is_directory(status)) {
      // A StagedFolder of an interrupted run: the half-written output.
      if (fs::remove_all(entry.path(), type_ec) > 0 && !type_ec) {
        ++removed;
        LogWarning() << "removed " << entry.path().string()
                     << ", a temporary folder left by an interrupted samp run (process " << pid << ")";
      }
      continue;
    }
    if (!fs::is_regular_file(status) && !fs::is_symlink(status)) continue;
    if (fs::remove(entry.path(), type_ec)) {
      ++removed;
      LogWarning() << "removed " << entry.path().string()
                   << ", a temporary file left by an interrupted samp run (process " << pid << ")";
    }
  }
  return removed;
}

namespace {

// RemoveOrphanTemporaries(folder) the first time this process writes there.
void RemoveOrphanTemporariesOnce(const std::string& folder) {
  static std::mutex cleaned_mutex;
  static std::set<std::string> cleaned_folders;
  std::lock_guard<std::mutex> lock(cleaned_mutex);
  if (cleaned_folders.insert(folder).second) RemoveOrphanTemporaries(folder);
}

// ".tmp.<pid>.<n>.<name>", cut to a file name's 255 bytes: a long `name`
// (241-255 bytes, which the target itself may have) keeps its end, so that
// the temporary still has the target's extension.
std::string TemporaryName(const std::string& name) {
  constexpr size_t kMaxFileName = 255;
  const std::string prefix = ".tmp." + std::to_string(::getpid()) + "." + std::to_string(g_counter++) + ".";
  const size_t room = kMaxFileName - prefix.size();
  return prefix + (name.size() <= room ? name : name.substr(name.size() - room));
}

}  // namespace

void RemoveTemporariesOnSignal() {
  static std::once_flag once;
  std::call_once(once, [] {
    struct sigaction action;
    std::memset(&action, 0, sizeof(action));
    action.sa_handler = &RemoveTemporariesAndReraise;
    sigemptyset(&action.sa_mask);
    for (int signal_number : {SIGINT, SIGTERM, SIGHUP}) ::sigaction(signal_number, &action, nullptr);
  });
}

void WriteBytesChecked(const std::string& path, const std::string& bytes, const std::string& name_for_errors) {
  const std::string& name = name_for_errors.empty() ? path : name_for_errors;
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  SAMP_CHECK(fd >= 0) << "cannot write " << name << ": cannot create " << path << ": " << std::strerror(errno);
  auto fail = [&](const char* step, int error) {
    ::close(fd);
    SAMP_THROW() << "cannot write " << name << ": " << step << " " << path << " failed after "
                 << "writing part of its " << bytes.size() << " bytes: " << std::strerror(error);
  };
  size_t written = 0;
  while (written < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + written, bytes.size() - written);
    if (n < 0) {
      if (errno == EINTR) continue;
      fail("write to", errno);
    }
    if (n == 0) fail("write to", EIO);  // no progress and no error: do not loop forever
    written += size_t(n);
  }
  if (::fsync(fd) != 0) fail("fsync of", errno);
  if (::close(fd) != 0) {
    SAMP_THROW() << "cannot write " << name << ": close of " << path << " failed: " << std::strerror(errno);
  }
}

namespace {

// fsync(path) as a check of a file another library wrote: errors of delayed
// writes (ENOSPC, EIO) surface here at the latest.
void SyncFileChecked(const std::string& path, const std::string& name) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  SAMP_CHECK(fd >= 0) << "cannot write " << name << ": cannot reopen " << path << ": " << std::strerror(errno);
  if (::fsync(fd) != 0) {
    const int error = errno;
    ::close(fd);
    SAMP_THROW() << "cannot write " << name << ": fsync of " << path << " failed: " << std::strerror(error);
  }
  SAMP_CHECK(::close(fd) == 0) << "cannot write " << name << ": close of " << path
                               << " failed: " << std::strerror(errno);
}

// fsync of the folder after a rename into it (so that the new name survives
// a crash); best effort: a failure is a warning, the file is in place.
void SyncFolder(const std::string& folder) {
  const int fd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  if (::fsync(fd) != 0 && errno != EINVAL && errno != EROFS) {
    LogWarning() << "fsync of folder " << folder << " failed: " << std::strerror(errno);
  }
  ::close(fd);
}

}  // namespace

void WriteFileAtomically(const std::string& path,
                         const std::function<void(const std::string&)>& writer) {
  const fs::path target(path);
  SAMP_CHECK(!target.filename().empty()) << "cannot write " << path << ": no file name";
  std::error_code ec;
  const fs::file_status status = fs::symlink_status(target, ec);
  SAMP_CHECK(!fs::exists(status) || fs::is_regular_file(status))
      << "cannot write " << path << ": it exists and is " << KindOf(status)
      << "; samp replaces only regular files";
  if (target.has_parent_path()) {
    fs::create_directories(target.parent_path(), ec);
    SAMP_CHECK(!ec) << "cannot create directory " << target.parent_path().string() << ": "
                    << ec.message();
  }
  const std::string folder = target.has_parent_path() ? target.parent_path().string() : ".";
  RemoveOrphanTemporariesOnce(folder);
  // The temporary keeps the target's extension: some writers pick the format from it.
  const std::string temporary = (target.parent_path() / TemporaryName(target.filename().string())).string();
  const int slot = RegisterTemporary(temporary);
  try {
    writer(temporary);
    SAMP_CHECK(fs::exists(temporary)) << "writer did not create " << temporary;
    SyncFileChecked(temporary, path);
    fs::rename(temporary, target, ec);
    SAMP_CHECK(!ec) << "cannot rename " << temporary << " to " << path << ": " << ec.message();
    SyncFolder(folder);
  } catch (...) {
    std::error_code ignored;
    fs::remove(temporary, ignored);
    UnregisterTemporary(slot);
    throw;
  }
  UnregisterTemporary(slot);
}

void WriteBytesAtomically(const std::string& path, const std::string& bytes,
                          const std::function<void(const std::string&)>& verify) {
  WriteFileAtomically(path, [&](const std::string& temporary) {
    WriteBytesChecked(temporary, bytes, path);
    if (verify) verify(temporary);
  });
}

void WriteTextFileAtomically(const std::string& path, const std::string& contents) {
  WriteBytesAtomically(path, contents);
}

StagedFolder::StagedFolder(const std::string& target) {
  SAMP_CHECK(!target.empty()) << "cannot write a folder: no path given";
  fs::path resolved = fs::path(target).lexically_normal();
  if (!resolved.has_filename() && resolved.has_parent_path()) resolved = resolved.parent_path();  // "out/"
  if (resolved.filename() == "." || resolved.filename() == "..") resolved = fs::absolute(resolved).lexically_normal();
  if (!resolved.has_filename() && resolved.has_parent_path()) resolved = resolved.parent_path();
  std::error_code ec;
  fs::file_status status = fs::symlink_status(resolved, ec);
  if (fs::is_symlink(status)) {
    const fs::path followed = fs::canonical(resolved, ec);
    SAMP_CHECK(!ec && fs::is_directory(followed, ec))
        << "cannot write folder " << target << ": it is a symbolic link that does not lead to a folder";
    resolved = followed;
    status = fs::symlink_status(resolved, ec);
  }
  SAMP_CHECK(!fs::exists(status) || fs::is_directory(status))
      << "cannot write folder " << target << ": it exists and is " << KindOf(status)
      << "; samp replaces only folders";
  SAMP_CHECK(resolved.has_filename() && resolved.has_relative_path())
      << "cannot write folder " << target << ": it has no parent folder to write beside";
  target_ = resolved.string();
  const fs::path parent = resolved.has_parent_path() ? resolved.parent_path() : fs::path(".");
  fs::create_directories(parent, ec);
  SAMP_CHECK(!ec) << "cannot create directory " << parent.string() << ": " << ec.message();
  RemoveOrphanTemporariesOnce(parent.string());
  temporary_ = (parent / TemporaryName(resolved.filename().string())).string();
  slot_ = RegisterTemporary(temporary_, /*folder=*/true);
  // The output keeps the target's name inside the temporary folder (what is
  // written there may record its folder's name, e.g. a page title).
  path_ = (fs::path(temporary_) / resolved.filename()).string();
  fs::create_directories(path_, ec);
  if (ec) {
    UnregisterTemporary(slot_);
    std::error_code ignored;
    fs::remove_all(temporary_, ignored);
    SAMP_THROW() << "cannot create folder " << path_ << ": " << ec.message();
  }
}

StagedFolder::~StagedFolder() {
  if (!temporary_.empty()) {
    std::error_code ignored;
    fs::remove_all(temporary_, ignored);
  }
  UnregisterTemporary(slot_);
}

namespace {

// Relative paths of every file (not folder) under `folder`, sorted.
std::vector<std::string> ListFilesRecursively(const fs::path& folder) {
  std::vector<std::string> files;
  std::error_code ec;
  for (fs::recursive_directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    std::error_code type_ec;
    if (it->is_directory(type_ec) && !it->is_symlink(type_ec)) continue;
    files.push_back(it->path().lexically_relative(folder).generic_string());
  }
  SAMP_CHECK(!ec) << "cannot list folder " << folder.string() << ": " << ec.message();
  std::sort(files.begin(), files.end());
  return files;
}

std::string RandomRunId() {
  std::random_device device;
  std::ostringstream id;
  for (int i = 0; i < 4; ++i) {
    char part[9];
    std::snprintf(part, sizeof(part), "%08x", unsigned(device()));
    id << part;
  }
  return id.str();
}

constexpr char kMarkerFirstLine[] = "samp output folder";

}  // namespace

bool CheckReplaceableOutputFolder(const std::string& folder, const std::string& why) {
  std::error_code ec;
  const fs::file_status status = fs::status(folder, ec);
  if (!fs::exists(status)) return false;
  SAMP_CHECK(fs::is_directory(status)) << "output folder " << folder << " exists and is not a folder" << why;
  const bool empty = fs::is_empty(folder, ec);
  SAMP_CHECK(!ec) << "cannot list output folder " << folder << ": " << ec.message();
  if (empty) return false;
  const fs::path marker = fs::path(folder) / kOutputFolderMarker;
  std::set<std::string> listed;
  bool valid = false;
  if (fs::is_regular_file(fs::symlink_status(marker, ec))) {
    std::ifstream in(marker, std::ios::binary);
    std::string line;
    valid = std::getline(in, line) && line == kMarkerFirstLine && std::getline(in, line) &&
            line.rfind("run_id ", 0) == 0;
    while (valid && std::getline(in, line)) {
      if (line.rfind("file ", 0) == 0) listed.insert(line.substr(5));
    }
  }
  SAMP_CHECK(valid) << "output folder " << folder << " is not empty and was not made by samp (it has no valid "
                    << kOutputFolderMarker << " marker file)" << why
                    << "; samp replaces only folders it made: give a new or empty folder";
  std::vector<std::string> foreign;
  for (const std::string& file : ListFilesRecursively(folder)) {
    if (file != kOutputFolderMarker && listed.count(file) == 0) foreign.push_back(file);
  }
  if (!foreign.empty()) {
    std::ostringstream list;
    for (size_t i = 0; i < foreign.size() && i < 20; ++i) list << (i ? ", " : "") << foreign[i];
    if (foreign.size() > 20) list << " and " << foreign.size() - 20 << " more";
    SAMP_THROW() << "output folder " << folder << " holds " << foreign.size()
                 << " file(s) samp did not write: " << list.str() << why
                 << "; samp replaces only folders it made: move them away or give another folder";
  }
  return true;
}

void RecordInOutputFolder(const std::string& folder, const std::vector<std::string>& files) {
  const fs::path marker = fs::path(folder) / kOutputFolderMarker;
  std::error_code ec;
  if (!fs::is_regular_file(fs::symlink_status(marker, ec))) return;
  std::ifstream in(marker, std::ios::binary);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (text.rfind(std::string(kMarkerFirstLine) + "\nrun_id ", 0) != 0) return;
  std::set<std::string> listed;
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("file ", 0) == 0) listed.insert(line.substr(5));
  }
  const fs::path base = fs::weakly_canonical(fs::absolute(folder), ec);
  bool added = false;
  for (const std::string& file : files) {
    const fs::path relative = fs::weakly_canonical(fs::absolute(file), ec).lexically_relative(base);
    if (ec || relative.empty() || *relative.begin() == ".." || relative == kOutputFolderMarker) continue;
    if (listed.insert(relative.generic_string()).second) {
      if (!text.empty() && text.back() != '\n') text += '\n';
      text += "file " + relative.generic_string() + "\n";
      added = true;
    }
  }
  if (added) WriteTextFileAtomically(marker.string(), text);
}

bool SameFile(const std::string& a, const std::string& b) {
  struct stat sa, sb;
  if (::stat(a.c_str(), &sa) != 0 || ::stat(b.c_str(), &sb) != 0) return false;
  return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

bool IsInsideFolder(const std::string& path, const std::string& folder) {
  std::error_code ec;
  fs::path resolved = fs::weakly_canonical(fs::absolute(path), ec);
  if (ec) resolved = fs::absolute(path).lexically_normal();
  fs::path resolved_folder = fs::weakly_canonical(fs::absolute(folder), ec);
  if (ec) resolved_folder = fs::absolute(folder).lexically_normal();
  const fs::path relative = resolved.lexically_relative(resolved_folder);
  if (!relative.empty() && *relative.begin() != "..") return true;
  struct stat folder_stat;
  if (::stat(resolved_folder.c_str(), &folder_stat) != 0) return false;
  for (fs::path p = resolved;; p = p.parent_path()) {
    struct stat s;
    if (::stat(p.c_str(), &s) == 0 && s.st_dev == folder_stat.st_dev && s.st_ino == folder_stat.st_ino) return true;
    if (!p.has_relative_path()) break;
  }
  return false;
}

void StagedFolder::Commit() {
  SAMP_CHECK(!committed_) << "StagedFolder " << target_ << ": committed twice";
  {
    // The marker lists every file of the run: a later run replaces the folder
    // only while it holds nothing else.
    run_id_ = RandomRunId();
    std::ostringstream marker;
    marker << kMarkerFirstLine << "\nrun_id " << run_id_ << "\n";
    for (const std::string& file : ListFilesRecursively(path_)) {
      if (file != kOutputFolderMarker) marker << "file " << file << "\n";
    }
    WriteBytesChecked((fs::path(path_) / kOutputFolderMarker).string(), marker.str(),
                      (fs::path(target_) / kOutputFolderMarker).string());
  }
  std::error_code ec;
  const fs::file_status status = fs::symlink_status(target_, ec);
  SAMP_CHECK(!fs::exists(status) || fs::is_directory(status))
      << "cannot replace " << target_ << ": it is now " << KindOf(status) << "; samp replaces only folders";
  if (fs::exists(status)) {
    // Swap the new folder and the previous one in one step; the temporary
    // folder then holds the previous one, removed below (or, if this process
    // dies first, by the next run).
    bool swapped = false;
#ifdef RENAME_EXCHANGE
    if (::renameat2(AT_FDCWD, path_.c_str(), AT_FDCWD, target_.c_str(), RENAME_EXCHANGE) == 0) {
      swapped = true;
    } else {
      SAMP_CHECK(errno == EINVAL || errno == ENOSYS || errno == ENOTSUP)
          << "cannot replace " << target_ << " by " << path_ << ": " << std::strerror(errno);
    }
#endif
    if (!swapped) {
      // No atomic exchange on this file system: the previous folder moves into
      // the temporary one, then the new one into place.
      const fs::path previous = fs::path(temporary_) / ".previous";
      fs::rename(target_, previous, ec);
      SAMP_CHECK(!ec) << "cannot move " << target_ << " aside: " << ec.message();
      fs::rename(path_, target_, ec);
      if (ec) {
        std::error_code ignored;
        fs::rename(previous, target_, ignored);
        SAMP_THROW() << "cannot rename " << path_ << " to " << target_ << ": " << ec.message();
      }
    }
    replaced_ = true;
  } else {
    fs::rename(path_, target_, ec);
    SAMP_CHECK(!ec) << "cannot rename " << path_ << " to " << target_ << ": " << ec.message();
  }
  committed_ = true;
  fs::remove_all(temporary_, ec);
  if (ec) {
    LogWarning() << "could not remove " << temporary_ << " (the previous contents of " << target_
                 << "): " << ec.message() << "; the next samp run beside it removes it";
  }
  temporary_.clear();
  UnregisterTemporary(slot_);
  slot_ = -1;
}

}  // namespace samp
