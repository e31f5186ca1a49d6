// The fps part of `axon demo`: simulated positioners on a virtual bus driven by the host driver.
#pragma once

#include <utility>  // before asio/awaitable.hpp, which uses std::exchange without it (Boost 1.74)

#include <boost/asio/any_io_executor.hpp>
#include <boost/asio/awaitable.hpp>

#include <functional>

namespace axon::app {

// Prints what it does to stdout; throws axon::Exception when a step fails. `set_on_signal` is
// run_command's signal hook: a stop signal stops every simulated robot before the demo ends.
boost::asio::awaitable<void> demo_fps(boost::asio::any_io_executor ex,
                                      std::function<void(std::function<void()>)> set_on_signal);

}  // namespace axon::app
