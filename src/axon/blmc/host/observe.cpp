#include "axon/blmc/host/observe.hpp"

#include "axon/blmc/host/error.hpp"
#include "axon/blmc/host/session_log.hpp"
#include "axon/core/wakeup.hpp"

namespace axon::blmc::host {

namespace {

// Whether `duration` (0: no limit) has passed since `t0` on the board's clock.
bool over(const Board& board, core::TimePoint t0, core::Duration duration) {
  return duration > core::Duration::zero() && board.clock().now() - t0 >= duration;
}

}  // namespace

asio::awaitable<Result<std::size_t>> watch_status(Board& board, core::Duration duration,
                                                  std::function<bool(const protocol::Status&)> on_status) {
  const auto t0 = board.clock().now();
  std::size_t handed = 0;
  while (!board.interrupted()) {
    auto st = co_await board.wait_status(board.options().status_timeout);
    if (!st) {
      if (st.error() == HostErrc::interrupted) break;
      co_return st.error();
    }
    ++handed;
    if (!on_status(st.value())) break;
    if (duration <= core::Duration::zero() || over(board, t0, duration)) break;
  }
  co_return handed;
}

asio::awaitable<bool> monitor(Board& board, core::Duration refresh, core::Duration duration,
                              std::function<bool(double t_s, const Measurements& m)> on_sample) {
  const auto t0 = board.clock().now();
  while (!board.interrupted() && !board.closed()) {
    co_await core::sleep_for(refresh);
    const double t = std::chrono::duration<double>(board.clock().now() - t0).count();
    if (!on_sample(t, board.latest())) co_return false;
    if (over(board, t0, duration)) break;
  }
  co_return true;
}

asio::awaitable<std::uint64_t> record(Board& board, can::CandumpWriter& log, std::string iface, core::Duration duration) {
  std::uint64_t written = 0;
  board.set_tap(candump_tap(log, std::move(iface), &written));
  const auto t0 = board.clock().now();
  while (!board.interrupted() && !board.closed()) {
    co_await core::sleep_for(std::chrono::milliseconds(100));
    if (over(board, t0, duration)) break;
  }
  board.set_tap({});
  (void)log.flush();
  co_return written;
}

}  // namespace axon::blmc::host
