#include "axon/blmc/host/motor_session.hpp"

#include "axon/blmc/host/error.hpp"
#include "axon/can/open.hpp"

#include <boost/asio/co_spawn.hpp>
#include <boost/asio/io_context.hpp>
#include <fmt/format.h>

#include <spdlog/spdlog.h>

#include <memory>

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

Result<void> disable_over_new_connection(const can::BusSpec& spec, core::Duration timeout) {
  Result<void> result = Error(HostErrc::timeout, fmt::format("{}: no way to the board within {:.1f} s", spec.to_string(),
                                                             std::chrono::duration<double>(timeout).count()));
  asio::io_context io;  // after `result`: the coroutine's frame goes first
  asio::co_spawn(
      io,
      [&]() -> asio::awaitable<void> {
        auto b = co_await can::open_bus(io.get_executor(), spec);
        if (!b) {
          result = b.error();
          co_return;
        }
        auto bus = std::move(b).value();
        {
          Board board(*bus);
          result = co_await board.disable();
        }
        auto f = co_await bus->flush(std::chrono::seconds(1));
        (void)f;
        // The board's reader, woken by the close, resumes after the bus is gone: can::Bus allows it.
        bus->close();
      },
      [](std::exception_ptr) {});
  io.run_for(timeout);
  return result;
}

}  // namespace axon::blmc::host
