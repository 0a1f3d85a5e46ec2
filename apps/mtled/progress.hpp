#pragma once
#include <atomic>
#include <chrono>
#include <string>

#include "mtled/io/run_outputs.hpp"

namespace mtled::app {

// A one-line progress display on stderr, redrawn at most every 0.25 s, and only when stderr is a terminal:
// logs and CI output stay clean.
class Progress {
 public:
  explicit Progress(bool enabled);
  ~Progress();
  // Whether a redraw is due: callers build the text only then (not at every step).
  bool due() const;
  void draw(double fraction, const std::string& text);
  void finish();

 private:
  bool enabled_;
  bool drawn_ = false;
  std::chrono::steady_clock::time_point start_, last_;
};

// The run's terminal: the progress display after every step, and the end of the run (RunStopped "interrupted") once
// `interrupted` is set (by Ctrl-C).
class ProgressWriter final : public OutputWriter {
 public:
  ProgressWriter(bool enabled, const std::atomic<bool>& interrupted) : progress_(enabled), interrupted_(interrupted) {}
  std::string name() const override { return "progress"; }
  void before_run(const RunContext& run, const StepRecord& initial) override {
    run_ = &run;
    after_step(initial);
  }
  void after_step(const StepRecord& step) override;
  bool reads_displacement(long) const override { return false; }

 private:
  void complete(const StepRecord&) override { progress_.finish(); }
  const RunContext* run_ = nullptr;
  Progress progress_;
  const std::atomic<bool>& interrupted_;
};

}  // namespace mtled::app
