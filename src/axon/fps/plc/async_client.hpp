// AsyncPlc: the blocking PlcClient run on a thread of its own, awaited from coroutines.
//
// Every call is handed to a one-thread pool that owns the PlcClient (libmodbus contexts are not
// thread-safe, and one thread keeps the calls in order); the awaiting coroutine resumes on its own
// executor when the call is done. A PLC that does not answer costs its timeout on that thread
// only: the io_context thread keeps serving the CAN buses meanwhile.
#pragma once

#include "axon/fps/plc/client.hpp"

#include <utility>  // before Asio (Boost 1.74's awaitable.hpp uses std::exchange)

#include <boost/asio/awaitable.hpp>
#include <boost/asio/co_spawn.hpp>
#include <boost/asio/thread_pool.hpp>
#include <boost/asio/use_awaitable.hpp>

#include <memory>
#include <optional>
#include <type_traits>

namespace axon::fps::plc {

class AsyncPlc {
 public:
  AsyncPlc(net::Endpoint endpoint, RegisterMap map = {}, PlcClientOptions options = {});
  AsyncPlc(const AsyncPlc&) = delete;
  AsyncPlc& operator=(const AsyncPlc&) = delete;
  ~AsyncPlc();  // waits for the call running now, if any

  // Runs f(client) on the PLC thread; f returns a Result.
  template <class F>
  auto call(F f) -> boost::asio::awaitable<std::invoke_result_t<F, PlcClient&>> {
    using R = std::invoke_result_t<F, PlcClient&>;
    PlcClient* c = client_.get();
    // The pool's completion resumes us on our own executor (the handler's associated executor).
    auto fn = [c, f = std::move(f)]() mutable -> boost::asio::awaitable<std::optional<R>> {
      co_return std::optional<R>(f(*c));
    };
    auto r = co_await boost::asio::co_spawn(pool_, std::move(fn), boost::asio::use_awaitable);
    co_return std::move(*r);
  }

  boost::asio::awaitable<Result<PlcStatus>> status();
  boost::asio::awaitable<Result<void>> set_relay(Relay r, bool on);
  boost::asio::awaitable<Result<void>> set_positioner_power(int sextant, bool on);
  boost::asio::awaitable<Result<void>> set_gateway_power(int sextant, bool on);
  boost::asio::awaitable<Result<void>> pulse_sync_line(core::Duration hold);

  [[nodiscard]] const net::Endpoint& endpoint() const noexcept { return client_->endpoint(); }
  [[nodiscard]] const RegisterMap& map() const noexcept { return client_->map(); }

 private:
  std::unique_ptr<PlcClient> client_;
  boost::asio::thread_pool pool_{1};
};

}  // namespace axon::fps::plc
