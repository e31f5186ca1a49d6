// A scripted stand-in for positioners on a virtual bus, for testing the command client without the
// simulator: every request is recorded and handed to a script that says what to send back (any
// frames, each after an optional delay, or nothing at all).
#pragma once

#include "axon/can/virtual_bus.hpp"
#include "axon/core/wakeup.hpp"
#include "axon/fps/protocol/message.hpp"

#include <boost/asio/co_spawn.hpp>
#include <boost/asio/detached.hpp>
#include <boost/asio/io_context.hpp>
#include <gtest/gtest.h>

#include <chrono>
#include <functional>
#include <memory>
#include <vector>

namespace axon::fps::host::testing {

using namespace std::chrono_literals;

struct Outgoing {
  can::Frame frame;
  core::Duration delay{0};
};

// A reply frame from `positioner` to request `m` (copies command and uid).
inline can::Frame reply_to(const protocol::Message& m, std::uint16_t positioner,
                           protocol::ResponseCode code = protocol::ResponseCode::accepted,
                           protocol::Payload payload = {}) {
  return protocol::make_reply(positioner, m.id.command, m.id.uid, code, payload).value();
}

// An unsolicited frame (uid 0) from `positioner`.
inline can::Frame unsolicited(std::uint16_t positioner, protocol::CommandId c,
                              protocol::ResponseCode code = protocol::ResponseCode::accepted) {
  return protocol::make_reply(positioner, protocol::number(c), 0, code, {}).value();
}

class FakeDevice {
 public:
  using Script = std::function<std::vector<Outgoing>(const protocol::Message&)>;

  FakeDevice(can::VirtualBus& medium, Script script) : bus_(medium.attach("fake")), script_(std::move(script)) {
    asio::co_spawn(bus_->get_executor(), loop(), asio::detached);
  }

  void set_script(Script s) { script_ = std::move(s); }
  [[nodiscard]] const std::vector<protocol::Message>& requests() const { return requests_; }
  [[nodiscard]] std::size_t count(protocol::CommandId c) const {
    std::size_t n = 0;
    for (const auto& m : requests_) n += m.id.command == protocol::number(c) ? 1 : 0;
    return n;
  }
  can::Bus& bus() { return *bus_; }

  // Sends a frame now (from a test coroutine).
  asio::awaitable<void> send(const can::Frame& f) { EXPECT_TRUE((co_await bus_->send(f)).has_value()); }

  void stop() { stopping_ = true; }
  [[nodiscard]] bool stopped() const { return done_; }

 private:
  asio::awaitable<void> loop() {
    while (!stopping_) {
      auto f = co_await bus_->receive(20ms);
      if (!f) {
        if (f.error() == can::CanErrc::timeout) continue;
        break;
      }
      auto m = protocol::from_frame(f.value());
      if (!m) continue;
      requests_.push_back(m.value());
      for (auto& out : script_(m.value())) {
        if (out.delay > core::Duration::zero()) {
          asio::co_spawn(bus_->get_executor(), delayed(out), asio::detached);
        } else {
          (void)co_await bus_->send(out.frame);
        }
      }
    }
    done_ = true;
  }

  asio::awaitable<void> delayed(Outgoing out) {
    co_await core::sleep_for(out.delay);
    if (!stopping_) (void)co_await bus_->send(out.frame);
  }

  std::unique_ptr<can::Bus> bus_;
  Script script_;
  std::vector<protocol::Message> requests_;
  bool stopping_ = false;
  bool done_ = false;
};

// A device that never answers.
inline FakeDevice::Script silent() {
  return [](const protocol::Message&) { return std::vector<Outgoing>{}; };
}

}  // namespace axon::fps::host::testing
