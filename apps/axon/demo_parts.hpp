// The parts of `axon demo` after CAN and fps, one file each: every family against its simulator.
#pragma once

#include <utility>  // before asio/awaitable.hpp, which uses std::exchange without it (Boost 1.74)

#include <boost/asio/any_io_executor.hpp>
#include <boost/asio/awaitable.hpp>

namespace axon::app {

// blmc: a simulated board under PD control in the real-time loop (demo_blmc.cpp). Exit code.
boost::asio::awaitable<int> demo_blmc(boost::asio::any_io_executor ex);

// c4g: a robot program on the controller simulator against the PC server (demo_c4g.cpp). Exit code.
int demo_c4g();

}  // namespace axon::app
