#include "axon/core/progress.hpp"

#include <unistd.h>

namespace axon::core {

Progress::Progress(std::FILE* out, ProgressOptions options, const Clock& clock)
    : out_(out),
      options_(options),
      clock_(clock),
      terminal_(options.terminal >= 0 ? options.terminal == 1 : ::isatty(::fileno(out)) == 1),
      start_(clock.now()) {}

Progress::~Progress() { finish(); }

bool Progress::update(std::string_view text) {
  const auto now = clock_.now();
  if (now - start_ < options_.quiet_for) return false;
  if (reports_ > 0 && now - last_ < (terminal_ ? options_.terminal_interval : options_.interval)) return false;
  last_ = now;
  ++reports_;
  if (terminal_) {
    const std::size_t pad = width_ > text.size() ? width_ - text.size() : 0;
    std::fprintf(out_, "\r%.*s%*s", static_cast<int>(text.size()), text.data(), static_cast<int>(pad), "");
    width_ = text.size();
    open_line_ = true;
  } else {
    std::fprintf(out_, "%.*s\n", static_cast<int>(text.size()), text.data());
  }
  std::fflush(out_);
  return true;
}

void Progress::finish() {
  if (!open_line_) return;
  std::fputc('\n', out_);
  std::fflush(out_);
  open_line_ = false;
}

}  // namespace axon::core
