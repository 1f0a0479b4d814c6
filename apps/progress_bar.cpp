// ProgressBar (see progress_bar.hpp): "\r[#####     ] 12/60 frames, 3.4 s" on stderr, redrawn
// over itself with a carriage return, and erased with an ANSI clear-to-end-of-line when done.
#include "progress_bar.hpp"

#include <cstdio>

#include <unistd.h>

namespace tessera::cli {

ProgressBar::ProgressBar(std::size_t total, std::string unit)
    : total_(total),
      unit_(std::move(unit)),
      enabled_(total > 0 && isatty(STDERR_FILENO) == 1),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_) {}

ProgressBar::~ProgressBar() { finish(); }

void ProgressBar::update(std::size_t done) {
  if (!enabled_) return;
  const auto now = std::chrono::steady_clock::now();
  if (drawn_ && done < total_ && now - last_draw_ < std::chrono::milliseconds(100)) return;
  last_draw_ = now;
  draw(done);
}

void ProgressBar::draw(std::size_t done) {
  constexpr std::size_t kWidth = 30;
  const std::size_t filled = total_ == 0 ? kWidth : done * kWidth / total_;
  std::string bar(filled, '#');
  bar.resize(kWidth, ' ');
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  std::fprintf(stderr, "\r[%s] %zu/%zu %s, %.1f s", bar.c_str(), done, total_, unit_.c_str(),
               seconds);
  std::fflush(stderr);
  drawn_ = true;
}

void ProgressBar::finish() {
  if (!drawn_) return;
  std::fputs("\r\033[K", stderr);  // back to the line start, erase the line
  std::fflush(stderr);
  drawn_ = false;
}

}  // namespace tessera::cli
