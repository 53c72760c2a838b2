#include "libsamp/core/atomic_file.h"

#include <signal.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
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
  char path[kMaxTemporaryPath];
};
std::array<TemporarySlot, kMaxLiveTemporaries> g_temporaries;

// Registers `path` for removal on a signal; -1 when every slot is taken (the
// file is then removed only by the writer or by the next run).
int RegisterTemporary(const std::string& path) {
  if (path.size() + 1 > kMaxTemporaryPath) return -1;
  for (int i = 0; i < kMaxLiveTemporaries; ++i) {
    bool expected = false;
    if (g_temporaries[i].busy.compare_exchange_strong(expected, true)) {
      std::memcpy(g_temporaries[i].path, path.c_str(), path.size() + 1);
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

extern "C" void RemoveTemporariesAndReraise(int signal_number) {
  for (auto& slot : g_temporaries) {
    if (slot.ready.load()) ::unlink(slot.path);  // async-signal-safe
  }
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
    if (!entry.is_regular_file(type_ec) && !entry.is_symlink(type_ec)) continue;
    if (fs::remove(entry.path(), type_ec)) {
      ++removed;
      LogWarning() << "removed " << entry.path().string()
                   << ", a temporary file left by an interrupted samp run (process " << pid << ")";
    }
  }
  return removed;
}

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

void WriteFileAtomically(const std::string& path,
                         const std::function<void(const std::string&)>& writer) {
  static std::atomic<int> counter{0};
  static std::mutex cleaned_mutex;
  static std::set<std::string> cleaned_folders;
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
  {
    std::lock_guard<std::mutex> lock(cleaned_mutex);
    if (cleaned_folders.insert(folder).second) RemoveOrphanTemporaries(folder);
  }
  // The temporary keeps the target's extension: some writers pick the format from it.
  const std::string temporary =
      (target.parent_path() / (".tmp." + std::to_string(::getpid()) + "." +
                               std::to_string(counter++) + "." + target.filename().string()))
          .string();
  const int slot = RegisterTemporary(temporary);
  try {
    writer(temporary);
    SAMP_CHECK(fs::exists(temporary)) << "writer did not create " << temporary;
    fs::rename(temporary, target, ec);
    SAMP_CHECK(!ec) << "cannot rename " << temporary << " to " << path << ": " << ec.message();
  } catch (...) {
    std::error_code ignored;
    fs::remove(temporary, ignored);
    UnregisterTemporary(slot);
    throw;
  }
  UnregisterTemporary(slot);
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
