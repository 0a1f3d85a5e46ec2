#include "mtled/log.hpp"

#include <spdlog/sinks/basic_file_sink.h>
#include <spdlog/sinks/stdout_color_sinks.h>

namespace mtled {

namespace {

thread_local spdlog::logger* thread_logger = nullptr;  // a ThreadLogFile's, while it lives

}  // namespace

spdlog::logger& log() {
  if (thread_logger) return *thread_logger;
  static std::shared_ptr<spdlog::logger> logger = [] {
    auto l = spdlog::stderr_color_mt("mtled");
    l->set_pattern("%^%l%$: %v");
    l->set_level(spdlog::level::info);
    return l;
  }();
  return *logger;
}

void set_log_level(const std::string& level) { log().set_level(spdlog::level::from_str(level)); }

ThreadLogFile::ThreadLogFile(const std::filesystem::path& file, const std::string& level)
    : logger_(std::make_shared<spdlog::logger>(
          "mtled", std::make_shared<spdlog::sinks::basic_file_sink_st>(file.string(), true))),
      previous_(thread_logger) {
  logger_->set_pattern("%l: %v");
  logger_->set_level(spdlog::level::from_str(level));
  logger_->flush_on(spdlog::level::trace);
  thread_logger = logger_.get();
}

ThreadLogFile::~ThreadLogFile() { thread_logger = previous_; }

}  // namespace mtled
