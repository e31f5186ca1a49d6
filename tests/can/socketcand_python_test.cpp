// Interoperability: Debian's python-can 4.1 socketcand client (a child process running
// tests/integration/python_can_socketcand.py --connect) against the server over a virtual bus.
#include "axon/can/socketcand_server.hpp"
#include "axon/can/virtual_bus.hpp"

#include <boost/asio/io_context.hpp>
#include <boost/asio/post.hpp>
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <future>
#include <string>
#include <thread>
#include <sys/wait.h>

namespace axon::can {
namespace {

constexpr const char* kPython = "/usr/bin/python3";

// Runs a shell command; returns its exit status and what it printed (stdout and stderr).
std::pair<int, std::string> run_command(const std::string& command) {
  std::string output;
  FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  if (pipe == nullptr) return {-1, "popen failed"};
  char buf[4096];
  std::size_t n = 0;
  while ((n = std::fread(buf, 1, sizeof buf, pipe)) > 0) output.append(buf, n);
  const int status = ::pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, output};
}

TEST(SocketcandPython, PythonCanClientsExchangeFramesThroughTheServer) {
  if (!std::filesystem::exists(kPython) || run_command(std::string(kPython) + " -c 'import can'").first != 0)
    GTEST_SKIP() << "python3-can is not installed";
  const auto script = std::filesystem::path(AXON_TESTS_DIR) / "integration" / "python_can_socketcand.py";
  ASSERT_TRUE(std::filesystem::exists(script)) << script;

  asio::io_context io;
  VirtualBusRegistry registry(io.get_executor());
  auto vcan0 = registry.add("vcan0").value();
  auto observer = vcan0->attach("observer");
  auto server = std::make_unique<SocketcandServer>(io.get_executor(), registry, net::Endpoint{"127.0.0.1", 0});
  const auto port = server->local_endpoint().port;
  auto guard = asio::make_work_guard(io);
  std::thread io_thread([&] { io.run(); });

  const auto [status, output] =
      run_command(std::string(kPython) + " " + script.string() + " --connect 127.0.0.1:" + std::to_string(port));

  // Collect what the server and a plain virtual node saw, on the io thread, then stop.
  std::promise<std::tuple<SocketcandServerStats, std::uint64_t, std::vector<Frame>>> seen;
  asio::post(io, [&] {
    std::vector<Frame> frames;
    while (auto f = observer->try_receive()) frames.push_back(*f);
    seen.set_value({server->stats(), observer->stats().frames_in, frames});
    server->stop();
    observer->close();
    guard.reset();
  });
  auto [stats, observed, frames] = seen.get_future().get();
  io.stop();
  io_thread.join();

  EXPECT_EQ(status, 0) << output;
  EXPECT_NE(output.find("ok: 38 frames a -> b and 300 frames b -> a"), std::string::npos) << output;
  EXPECT_EQ(stats.clients_accepted, 2u);
  EXPECT_EQ(stats.frames_in, 338u);
  EXPECT_EQ(stats.frames_out, 338u);
  EXPECT_EQ(stats.errors, 0u) << output;
  // The axon side sees python-can's frames with the right id format (ids above 0x7FF: extended).
  EXPECT_EQ(observed, 338u);
  ASSERT_GE(frames.size(), 4u);
  EXPECT_EQ(frames[0], Frame::parse("100#").value());
  EXPECT_EQ(frames[2], Frame::parse("1ABCDE00#").value());
  EXPECT_EQ(frames[3], Frame::parse("00000800#").value());
  EXPECT_EQ(frames.back(), Frame::extended(0x12345 + 299 % 3, std::vector<std::uint8_t>{0x01, 0x2B, 0x01, 0x2B, 0x01, 0x2B, 0x01, 0x2B}).value());
}

}  // namespace
}  // namespace axon::can
