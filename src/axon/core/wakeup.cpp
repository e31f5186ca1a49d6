#include "axon/core/wakeup.hpp"

#include <boost/asio/redirect_error.hpp>
#include <boost/asio/this_coro.hpp>
#include <boost/asio/use_awaitable.hpp>

namespace axon::core {

namespace asio = boost::asio;

asio::awaitable<bool> Wakeup::wait_until(TimePoint deadline) {
  while (!notified_) {
    if (abandoned_ || std::chrono::steady_clock::now() >= deadline) co_return false;
    timer_.expires_at(deadline);
    boost::system::error_code ec;  // expiry and cancellation both just re-check the state
    co_await timer_.async_wait(asio::redirect_error(asio::use_awaitable, ec));
  }
  co_return true;
}

asio::awaitable<void> sleep_for(Duration d) {
  asio::steady_timer t(co_await asio::this_coro::executor, d);
  boost::system::error_code ec;
  co_await t.async_wait(asio::redirect_error(asio::use_awaitable, ec));
}

}  // namespace axon::core
