// The parts of `axon demo` after CAN and fps, one file each: every family against its simulator.
#pragma once

#include <functional>
#include <utility>  // before asio/awaitable.hpp, which uses std::exchange without it (Boost 1.74)

#include <boost/asio/any_io_executor.hpp>
#include <boost/asio/awaitable.hpp>

namespace axon::app {

// blmc: a simulated board under PD control in the real-time loop (demo_blmc.cpp); a stop signal
// ends the loop early (the motors are disabled as on every other way out). Exit code.
boost::asio::awaitable<int> demo_blmc(boost::asio::any_io_executor ex,
                                      std::function<void(std::function<void()>)> set_on_signal);

// c4g: a robot program on the controller simulator against the PC server (demo_c4g.cpp). Exit code.
int demo_c4g();

}  // namespace axon::app
