// Progress of long work (a plane move, a replay across a long gap, a firmware upgrade) for people
// and for logs alike. On a terminal one line is rewritten in place with a carriage return; into a
// file or a pipe, plain lines at most once per interval, so a log opened later reads cleanly and
// carries no '\r'. Not for real-time threads (it formats and writes).
#pragma once

#include "axon/core/clock.hpp"

#include <cstdio>
#include <string>
#include <string_view>

namespace axon::core {

struct ProgressOptions {
  Duration interval = std::chrono::seconds(1);  // shortest time between two lines into a file or pipe
  Duration terminal_interval = std::chrono::milliseconds(250);  // between two rewrites on a terminal
  // Reports start only after this long, so that work that ends quickly prints nothing but its result.
  Duration quiet_for = std::chrono::seconds(2);
  int terminal = -1;                            // 1 / 0: force; -1: ask isatty() of the stream
};

class Progress {
 public:
  explicit Progress(std::FILE* out = stderr, ProgressOptions options = {}, const Clock& clock = SteadyClock::instance());
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  // The current state, e.g. "move: 12.0 of 31.5 s, 480 of 500 robots moving". Written when the
  // quiet time and the interval since the last report have passed; returns whether it was.
  bool update(std::string_view text);
  // Ends the progress line on a terminal (the next output starts on a fresh line). Also done by the
  // destructor.
  void finish();

  [[nodiscard]] bool terminal() const noexcept { return terminal_; }
  [[nodiscard]] int reports() const noexcept { return reports_; }

 private:
  std::FILE* out_;
  ProgressOptions options_;
  const Clock& clock_;
  bool terminal_;
  TimePoint start_;
  TimePoint last_{};
  int reports_ = 0;
  std::size_t width_ = 0;  // of the line on the terminal, to blank a longer previous one
  bool open_line_ = false;
};

}  // namespace axon::core
