// Progress reporting for long work. On a terminal, a bar with rate and ETA
// redrawn in place on stderr; otherwise plain lines every 10 % or 10 s.
// Tick() is thread-safe and cheap (an atomic add; redraws are rate-limited).
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>

namespace samp {

class Progress {
 public:
  // `total` units of work; `enabled` = false makes every call a no-op.
  Progress(std::string label, int64_t total, bool enabled = true);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  void Tick(int64_t units = 1);
  // Prints the final state once (also called by the destructor).
  void Finish();

  // Formats seconds as "1h02m", "3m05s" or "12.3s".
  static std::string FormatDuration(double seconds);

 private:
  void Report(bool final_report);

  std::string label_;
  int64_t total_;
  bool enabled_;
  bool is_terminal_;
  bool finished_ = false;
  std::atomic<int64_t> done_{0};
  std::mutex mutex_;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_report_;
  int last_decile_ = 0;
};

}  // namespace samp
