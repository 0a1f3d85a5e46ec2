#pragma once
#include <chrono>
#include <string>

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

}  // namespace mtled::app
