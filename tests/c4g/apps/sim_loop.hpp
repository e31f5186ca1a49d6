// An application served against the controller simulator in-process, tick by tick and without
// sockets (deterministic), the way the Server hands packets over: init packet decoded and given to
// the app and Safety, each cyclic packet answered with the modes echoed, the switch tracker
// updated, the app called, Safety applied, the reply sent back to the controller.
#pragma once

#include "axon/c4g/apps/app.hpp"
#include "axon/c4g/host/safety.hpp"
#include "axon/c4g/host/switch_tracker.hpp"
#include "axon/c4g/protocol/mode.hpp"
#include "axon/c4g/sim/controller.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <string>

namespace axon::c4g::apps::test {

struct SimLoop {
  SimLoop(sim::Controller& c, App& a, host::SwitchTracker& t) : controller(c), app(a), tracker(t) {}

  sim::Controller& controller;
  App& app;
  host::SwitchTracker& tracker;
  host::Safety safety;
  protocol::InitPacket init;
  protocol::AxisMap map;
  protocol::Packet req, rep;
  std::uint64_t cycle = 0;
  std::string errors;  // the controller's error events, one per line

  // Runs for up to `max_s` of controller time or until the controller finishes; after every cyclic
  // packet the app answered (Safety applied, reply not yet sent) calls `served` (req and rep hold
  // the packet and the reply).
  void run(double max_s, const std::function<void()>& served) {
    namespace P = protocol;
    const auto ticks = static_cast<std::uint64_t>(max_s / controller.period_s());
    for (std::uint64_t k = 0; k < ticks && !controller.finished(); ++k) {
      const auto d = controller.begin_cycle();
      if (P::classify(d.size()) == P::DatagramKind::init) {
        init = P::decode_init(d).value();
        map = P::AxisMap::from_init(init).value();
        app.on_init(init, map);
        safety.configure(init, map);
        rep = P::Packet{};
        rep.num = init.protocol_number;
        rep.count = map.count();
      } else if (!d.empty()) {
        EXPECT_TRUE(P::decode_packet(d, req).ok());
        rep = P::Packet{};
        rep.num = req.num;
        rep.count = req.count;
        for (std::size_t i = 0; i < req.count; ++i) rep.axes[i].mode = req.axes[i].mode;
        if (cycle > 0 || init.open_axes > 0) {
          tracker.update(req, controller.period_s());
          const host::CycleContext ctx{req, &init, &map, cycle++, 0, &tracker};
          host::ReplyBuilder b(rep);
          app.on_cycle(ctx, b);
          safety.apply(req, rep);
          served();
        }
      }
      std::array<std::byte, P::kMaxPacketSize> out{};
      if (!d.empty() && P::encode_packet(rep, out).ok())
        controller.on_datagram(std::span<const std::byte>(out.data(), P::packet_size(rep.count)));
      controller.end_cycle();
      for (const auto& e : controller.take_events())
        if (e.level == sim::EventLevel::error) errors += e.name + ": " + e.text + "\n";
    }
  }
};

}  // namespace axon::c4g::apps::test
