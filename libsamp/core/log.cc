#include "libsamp/core/log.h"

#include <atomic>
#include <iostream>
#include <mutex>

namespace samp {
namespace {
std::atomic<int> g_level{static_cast<int>(LogLevel::kInfo)};
std::mutex g_mutex;
}  // namespace

void SetLogLevel(LogLevel level) { g_level = static_cast<int>(level); }
LogLevel GetLogLevel() { return static_cast<LogLevel>(g_level.load()); }

LogLine::~LogLine() {
  if (level_ < GetLogLevel()) return;
  static const char* kPrefix[] = {"debug: ", "", "warning: ", "error: "};
  std::lock_guard<std::mutex> lock(g_mutex);
  std::cerr << kPrefix[static_cast<int>(level_)] << stream_.str() << '\n' << std::flush;
}

}  // namespace samp
