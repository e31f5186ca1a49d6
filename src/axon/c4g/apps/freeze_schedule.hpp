// Active freezing (special mode 500, host::Server::request_freeze) on a schedule: freeze a given
// time after the start, release a given time after the controller shows 500, and requests from
// elsewhere (signals, a user interface) through request() / release(). Each request, release and
// state change is told in words ("freeze: requested (SIGUSR1)", "freeze: frozen", ...).
//
// Not for the cycle thread: poll() from the thread that waits on the server (e.g. in
// ServeSession::Hooks::on_poll); the server itself only sees atomics.
#pragma once

#include "axon/c4g/host/server.hpp"

#include <chrono>
#include <functional>
#include <optional>
#include <string>
#include <string_view>

namespace axon::c4g::apps {

struct FreezeScheduleOptions {
  double freeze_at_s = 0;   // request a freeze this long after construction (0: never)
  double freeze_for_s = 0;  // release this long after the controller shows 500 (0: only on release())
};

class FreezeSchedule {
 public:
  FreezeSchedule(host::Server& server, FreezeScheduleOptions options, std::function<void(const std::string&)> say);
  void request(std::string_view why);
  void release(std::string_view why);
  // Applies the schedule and tells state changes.
  void poll();
  // The server is about to stop: a freeze in force is released.
  void stopping();

 private:
  using Clock = std::chrono::steady_clock;
  host::Server& server_;
  FreezeScheduleOptions options_;
  std::function<void(const std::string&)> say_;
  Clock::time_point start_;
  bool at_done_;
  host::FreezeState shown_ = host::FreezeState::off;
  std::optional<Clock::time_point> frozen_since_;
};

}  // namespace axon::c4g::apps
