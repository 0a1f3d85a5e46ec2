#pragma once
#include <spdlog/spdlog.h>

#include <chrono>
#include <string_view>

namespace mtled {

// The one logger of the process (stderr). It lives in libmtled_core, which plugins share.
spdlog::logger& log();
// Level names: trace, debug, info, warn, error, off.
void set_log_level(const std::string& level);

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
