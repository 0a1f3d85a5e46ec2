#pragma once
#include <spdlog/spdlog.h>

namespace mtled {

// The one logger of the process (stderr). It lives in libmtled_core, which plugins share.
spdlog::logger& log();
// Level names: trace, debug, info, warn, error, off.
void set_log_level(const std::string& level);

}  // namespace mtled
