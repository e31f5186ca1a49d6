#include "axon/c4g/apps/freeze_schedule.hpp"

#include <fmt/format.h>

namespace axon::c4g::apps {

FreezeSchedule::FreezeSchedule(host::Server& server, FreezeScheduleOptions options, std::function<void(const std::string&)> say)
    : server_(server), options_(options), say_(std::move(say)), start_(Clock::now()), at_done_(options.freeze_at_s <= 0) {}

void FreezeSchedule::request(std::string_view why) {
  if (say_) say_(fmt::format("freeze: requested ({})", why));
  server_.request_freeze();
}

void FreezeSchedule::release(std::string_view why) {
  if (say_) say_(fmt::format("freeze: released ({})", why));
  server_.release_freeze();
}

void FreezeSchedule::poll() {
  const auto now = Clock::now();
  if (!at_done_ && now - start_ >= std::chrono::duration<double>(options_.freeze_at_s)) {
    at_done_ = true;
    request(fmt::format("--freeze-at {:.3f} s", options_.freeze_at_s));
  }
  const auto st = server_.freeze_state();
  if (st != shown_) {
    if (say_) say_(fmt::format("freeze: {}", host::to_string(st)));
    shown_ = st;
    frozen_since_.reset();
    if (st == host::FreezeState::frozen) frozen_since_ = now;
  }
  if (frozen_since_ && options_.freeze_for_s > 0 && server_.freeze_requested() &&
      now - *frozen_since_ >= std::chrono::duration<double>(options_.freeze_for_s))
    release(fmt::format("--freeze-for {:.3f} s", options_.freeze_for_s));
}

void FreezeSchedule::stopping() {
  if (server_.freeze_requested()) release("stopping");
}

}  // namespace axon::c4g::apps
