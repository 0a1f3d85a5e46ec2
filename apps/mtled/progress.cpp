#include "progress.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>

#include "scene_run.hpp"

namespace mtled::app {

Progress::Progress(bool enabled)
    : enabled_(enabled && ::isatty(STDERR_FILENO) != 0), start_(std::chrono::steady_clock::now()), last_(start_) {}

Progress::~Progress() { finish(); }

bool Progress::due() const {
  return enabled_ && (!drawn_ || std::chrono::steady_clock::now() - last_ >= std::chrono::milliseconds(250));
}

void Progress::draw(double fraction, const std::string& text) {
  if (!enabled_) return;
  const auto now = std::chrono::steady_clock::now();
  last_ = now;
  drawn_ = true;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const int width = 24;
  const int filled = static_cast<int>(std::clamp(fraction, 0.0, 1.0) * width);
  std::fprintf(stderr, "\r[%s%s] %3.0f%% %6.1fs  %s\033[K", std::string(static_cast<std::size_t>(filled), '#').c_str(),
               std::string(static_cast<std::size_t>(width - filled), '.').c_str(), 100.0 * fraction, elapsed, text.c_str());
  std::fflush(stderr);
}

void Progress::finish() {
  if (enabled_ && drawn_) {
    std::fprintf(stderr, "\n");
    drawn_ = false;
  }
}

}  // namespace mtled::app

namespace mtled::app {

void ProgressWriter::after_step(const StepRecord& step) {
  if (interrupted_) throw RunStopped("interrupted", "interrupted (Ctrl-C)");
  if (!progress_.due()) return;
  std::string text = fmt::format("step {}  t {:.4g} s", step.load.step, step.load.time);
  if (step.needle)
    text += fmt::format("  depth {:.2f} mm  force {:.4g} N  {}", 1e3 * step.needle->depth, step.needle->force,
                        to_string(step.needle->phase));
  // Once the load is on, a relaxation is most of a run: show how far it still has to go.
  if (step.load.load_fraction >= 1.0) {
    if (const auto relaxation = run_->integrator->report().relaxation)
      text += fmt::format("  relaxing: error {:.2g} (tolerance {:.2g})", relaxation->relative_error_bound,
                          relaxation->tolerance);
  }
  progress_.draw(step.load.load_fraction, text);
}

}  // namespace mtled::app
