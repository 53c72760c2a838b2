#include "libsamp/core/progress.h"

#include <unistd.h>

#include <cstdio>

#include "libsamp/core/log.h"

namespace samp {

Progress::Progress(std::string label, int64_t total, bool enabled)
    : label_(std::move(label)),
      total_(total > 0 ? total : 1),
      enabled_(enabled && GetLogLevel() <= LogLevel::kInfo),
      is_terminal_(::isatty(STDERR_FILENO) != 0),
      start_(std::chrono::steady_clock::now()),
      last_report_(start_) {}

Progress::~Progress() { Finish(); }

std::string Progress::FormatDuration(double seconds) {
  char buffer[32];
  if (seconds >= 3600.0) {
    std::snprintf(buffer, sizeof(buffer), "%dh%02dm", int(seconds / 3600), int(seconds / 60) % 60);
  } else if (seconds >= 60.0) {
    std::snprintf(buffer, sizeof(buffer), "%dm%02ds", int(seconds / 60), int(seconds) % 60);
  } else {
    std::snprintf(buffer, sizeof(buffer), "%.1fs", seconds);
  }
  return buffer;
}

void Progress::Tick(int64_t units) {
  if (!enabled_) return;
  const int64_t done = done_.fetch_add(units) + units;
  const auto now = std::chrono::steady_clock::now();
  const double since_last = std::chrono::duration<double>(now - last_report_).count();
  const int decile = int(10 * done / total_);
  const bool due = is_terminal_ ? since_last > 0.1 : (decile > last_decile_ || since_last > 10.0);
  if (due && done < total_) {
    std::unique_lock<std::mutex> lock(mutex_, std::try_to_lock);
    if (lock.owns_lock()) Report(false);
  }
}

void Progress::Finish() {
  if (!enabled_) return;
  std::lock_guard<std::mutex> lock(mutex_);
  if (finished_) return;
  finished_ = true;
  Report(true);
}

void Progress::Report(bool final_report) {
  const auto now = std::chrono::steady_clock::now();
  last_report_ = now;
  const int64_t done = std::min(done_.load(), total_);
  last_decile_ = int(10 * done / total_);
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const double fraction = double(done) / double(total_);
  std::string eta = "--";
  if (done > 0 && !final_report) eta = FormatDuration(elapsed * (1.0 - fraction) / fraction);
  char line[256];
  if (is_terminal_) {
    const int width = 30;
    const int filled = int(fraction * width);
    std::string bar(filled, '#');
    bar.resize(width, '.');
    std::snprintf(line, sizeof(line), "\r%s [%s] %lld/%lld %3.0f%% %s %s %s", label_.c_str(),
                  bar.c_str(), (long long)done, (long long)total_, 100.0 * fraction,
                  FormatDuration(elapsed).c_str(), final_report ? "" : "ETA",
                  final_report ? "" : eta.c_str());
    std::fprintf(stderr, "%s\033[K%s", line, final_report ? "\n" : "");
  } else {
    std::snprintf(line, sizeof(line), "%s: %lld/%lld (%.0f%%) elapsed %s%s%s\n", label_.c_str(),
                  (long long)done, (long long)total_, 100.0 * fraction,
                  FormatDuration(elapsed).c_str(), final_report ? "" : ", ETA ",
                  final_report ? "" : eta.c_str());
    std::fputs(line, stderr);
  }
  std::fflush(stderr);
}

}  // namespace samp
