#include "Progress.h"

#include <unistd.h>
#include <cstdio>

namespace cape::demo {

Progress::Progress(std::string label, long total)
    : label_(std::move(label)),
      total_(total > 0 ? total : 1),
      start_(std::chrono::steady_clock::now()),
      lastDraw_(start_),
      tty_(isatty(STDERR_FILENO) != 0) {}

void Progress::update(long done) {
  const auto now = std::chrono::steady_clock::now();
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  if (elapsed < 1.0) return;
  const double fraction = static_cast<double>(done) / static_cast<double>(total_);
  const double eta = fraction > 0.0 ? elapsed * (1.0 - fraction) / fraction : 0.0;
  if (tty_) {
    if (shown_ && now - lastDraw_ < std::chrono::milliseconds(100)) return;
    constexpr int kWidth = 30;
    const int filled = static_cast<int>(fraction * kWidth);
    std::fprintf(stderr, "\r%s [%.*s%*s] %3d%%  %ld/%ld  %.0fs left ", label_.c_str(), filled,
                 "##############################", kWidth - filled, "", static_cast<int>(fraction * 100.0),
                 done, total_, eta);
  } else {
    const int decile = static_cast<int>(fraction * 10.0);
    if (decile == lastDecile_) return;
    lastDecile_ = decile;
    std::fprintf(stderr, "%s: %d%% (%ld/%ld), %.0f s left\n", label_.c_str(), decile * 10, done, total_, eta);
  }
  std::fflush(stderr);
  shown_ = true;
  lastDraw_ = now;
}

void Progress::finish() {
  if (shown_ && tty_) std::fprintf(stderr, "\r%s done.%60s\n", label_.c_str(), "");
}

}  // namespace cape::demo
