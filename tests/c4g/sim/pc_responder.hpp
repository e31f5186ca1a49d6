// A minimal PC side for the simulator tests, independent of the server: answers every datagram with
// the protocol number it carries, echoing the axis modes with zero data, and lets a test change the
// reply or stay silent. Drives a sim::Controller tick by tick without sockets.
#pragma once

#include "axon/c4g/protocol/init_packet.hpp"
#include "axon/c4g/protocol/packet.hpp"
#include "axon/c4g/sim/controller.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace axon::c4g::sim::test {

namespace P = protocol;

struct Sent {
  std::vector<std::byte> bytes;
  P::Packet packet;  // decoded when cyclic
  bool cyclic = false;
  bool init = false;
};

class PcResponder {
 public:
  bool answer = true;
  // Called with the controller's packet and the reply pre-filled (number, modes echoed, data 0).
  std::function<void(const P::Packet&, P::Packet&)> fill;
  // Replaces the whole reply datagram (wrong sizes, garbage); empty: no override.
  std::function<std::vector<std::byte>(const P::Packet&)> raw;
  std::vector<Sent> sent;
  std::vector<Event> events;

  // One controller tick. Returns the datagram sent (may be empty).
  Sent tick(Controller& c) {
    const auto d = c.begin_cycle();
    Sent s;
    s.bytes.assign(d.begin(), d.end());
    if (!d.empty()) {
      if (P::classify(d.size()) == P::DatagramKind::init) {
        s.init = true;
        auto init = P::decode_init(d);
        EXPECT_TRUE(init.has_value());
        if (answer && init) {
          P::Packet r;
          r.num = init.value().protocol_number;
          r.count = static_cast<std::size_t>(init.value().open_axes);
          send(c, r);
        }
      } else {
        s.cyclic = true;
        EXPECT_TRUE(P::decode_packet(d, s.packet).ok());
        if (answer) {
          if (raw) {
            const auto bytes = raw(s.packet);
            c.on_datagram(bytes);
          } else {
            P::Packet r;
            r.num = s.packet.num;
            r.count = s.packet.count;
            for (std::size_t i = 0; i < r.count; ++i) r.axes[i].mode = s.packet.axes[i].mode;
            if (fill) fill(s.packet, r);
            send(c, r);
          }
        }
      }
    }
    c.end_cycle();
    for (auto& e : c.take_events()) events.push_back(std::move(e));
    sent.push_back(s);
    return s;
  }

  void run(Controller& c, int ticks) {
    for (int i = 0; i < ticks; ++i) tick(c);
  }
  // Ticks until pred() or the limit; returns whether pred() held.
  template <class F>
  bool run_until(Controller& c, F pred, int limit = 20000) {
    for (int i = 0; i < limit; ++i) {
      if (pred()) return true;
      tick(c);
    }
    return pred();
  }

  [[nodiscard]] std::size_t count_events(std::string_view name) const {
    std::size_t n = 0;
    for (const auto& e : events) n += e.name == name ? 1 : 0;
    return n;
  }
  [[nodiscard]] const Event* find_event(std::string_view name) const {
    for (const auto& e : events)
      if (e.name == name) return &e;
    return nullptr;
  }

  static void send(Controller& c, const P::Packet& r) {
    std::array<std::byte, P::kMaxPacketSize> buf{};
    const auto f = P::encode_packet(r, buf);
    ASSERT_TRUE(f.ok());
    c.on_datagram(std::span<const std::byte>(buf.data(), P::packet_size(r.count)));
  }
};

// The six-axis robot with short procedures, so tests run few ticks.
inline RobotConfig quick_robot() {
  RobotConfig r = six_axis_robot();
  r.drive_on_s = 0.02;
  r.drive_off_s = 0.01;
  r.scs.times = {0.004, 0.012, 0.004};  // T1 + T2 + T3 = 20 ms
  return r;
}

inline Controller make_controller(std::string_view yaml, RobotConfig robot = quick_robot(), ControllerOptions o = {}) {
  auto sc = Scenario::parse(yaml, "test.yaml");
  EXPECT_TRUE(sc.has_value()) << (sc ? "" : sc.error().detail);
  auto c = Controller::create(std::move(robot), std::move(sc).value(), o);
  EXPECT_TRUE(c.has_value());
  return std::move(c).value();
}

}  // namespace axon::c4g::sim::test
