#include "axon/blmc/host/motor_session.hpp"

#include <spdlog/spdlog.h>

namespace axon::blmc::host {

MotorSession::~MotorSession() {
  if (!active()) return;
  spdlog::error("{}: motor session abandoned with the motors enabled: queueing IqRef=0 and the disables",
                board_->options().name);
  board_->queue_disable();
}

asio::awaitable<Result<void>> MotorSession::enable() {
  started_ = true;
  auto r = co_await board_->enable();
  if (!r) {
    auto d = co_await end();
    (void)d;  // logged by end()
  }
  co_return r;
}

asio::awaitable<Result<void>> MotorSession::end() {
  if (!started_ || ended_) co_return end_result_;
  auto r = co_await board_->disable();
  ended_ = true;
  end_result_ = r;
  if (!r) spdlog::error("{}: could not disable the board (the motors may still be on): {}", board_->options().name,
                        r.error().message());
  co_return end_result_;
}

}  // namespace axon::blmc::host
