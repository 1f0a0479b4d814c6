// A one-line progress bar on stderr, drawn only when stderr is a terminal (so logs, pipes
// and tests see nothing of it), redrawn at most ten times a second and erased when done.
#pragma once

#include <chrono>
#include <cstddef>
#include <string>

namespace tessera::cli {

class ProgressBar {
 public:
  /// `total` units of work called `unit` ("frames"); draws nothing unless stderr is a tty.
  ProgressBar(std::size_t total, std::string unit);
  ~ProgressBar();
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  void update(std::size_t done);
  /// Erases the bar (also done by the destructor).
  void finish();

 private:
  void draw(std::size_t done);

  std::size_t total_;
  std::string unit_;
  bool enabled_;
  bool drawn_ = false;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_draw_;
};

}  // namespace tessera::cli
