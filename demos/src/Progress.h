// A progress bar on stderr for long runs: silent for the first second, then redrawn a few times a second
// (on a terminal) or printed every 10 % (when stderr is a file or a pipe).
#pragma once

#include <chrono>
#include <string>

namespace cape::demo {

class Progress {
 public:
  Progress(std::string label, long total);
  void update(long done);
  void finish();

 private:
  std::string label_;
  long total_;
  std::chrono::steady_clock::time_point start_, lastDraw_;
  bool shown_ = false;
  bool tty_ = false;
  int lastDecile_ = -1;
};

}  // namespace cape::demo
