#pragma once
#include <spdlog/spdlog.h>

#include <chrono>
#include <filesystem>
#include <memory>
#include <string_view>

namespace mtled {

// The one logger of the process (stderr). It lives in libmtled_core, which plugins share.
spdlog::logger& log();
// Level names: trace, debug, info, warn, error, off.
void set_log_level(const std::string& level);

// While it lives, log() on the thread that made it writes to `file` at `level` instead: a run in the calling process (a
// fit's forward run) keeps its messages in its own folder, as a child process's are. Other threads (a run's thread
// team) still log to stderr.
class ThreadLogFile {
 public:
  ThreadLogFile(const std::filesystem::path& file, const std::string& level);
  ~ThreadLogFile();
  ThreadLogFile(const ThreadLogFile&) = delete;
  ThreadLogFile& operator=(const ThreadLogFile&) = delete;

 private:
  std::shared_ptr<spdlog::logger> logger_;
  spdlog::logger* previous_;
};

// Where a long command's time goes, at debug level: each lap("what") logs the seconds since the previous lap.
class PhaseLog {
 public:
  void lap(std::string_view what) {
    const auto now = std::chrono::steady_clock::now();
    log().debug("{}: {:.2f} s", what, std::chrono::duration<double>(now - last_).count());
    last_ = now;
  }

 private:
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
};

}  // namespace mtled
