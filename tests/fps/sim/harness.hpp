// Drives one PositionerModel by hand: requests as the host would send them, time moved explicitly.
#pragma once

#include "axon/fps/protocol/message.hpp"
#include "axon/fps/protocol/payloads.hpp"
#include "axon/fps/sim/positioner_model.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace axon::fps::sim::testing {

using protocol::CommandId;
using protocol::Message;
using protocol::Payload;
using protocol::ResponseCode;
using protocol::StatusBit;
using namespace std::chrono_literals;

inline PositionerConfig test_config(std::uint16_t id = 7) {
  PositionerConfig c;
  c.id = id;
  return c;
}

inline Payload positions(double alpha_deg, double beta_deg) {
  return protocol::ArmPositions{protocol::Angle::from_degrees(alpha_deg).value(),
                                protocol::Angle::from_degrees(beta_deg).value()}
      .encode();
}
// The two arm values a reply carries (a bad payload fails the test).
inline protocol::ArmValues values(const Message& m) { return protocol::ArmValues::decode(m.payload.span()).value(); }
inline Payload two_u32(std::uint32_t a, std::uint32_t b) { return Payload().put_u32(a).put_u32(b); }
inline Payload two_i32(std::int32_t a, std::int32_t b) { return Payload().put_i32(a).put_i32(b); }
inline Payload point(double deg, double seconds) {
  return protocol::TrajectoryPoint{protocol::Angle::from_degrees(deg).value(),
                                   protocol::Time::from_seconds(seconds).value()}
      .encode();
}

struct Harness {
  explicit Harness(PositionerConfig c = test_config()) : model(std::move(c)) {}

  PositionerModel model;
  SimTime now{};
  std::uint8_t next_uid = 1;
  std::vector<Message> unsolicited;  // everything advance() produced

  std::uint16_t id() const { return model.id(); }

  // Sends a raw request (number, target, payload) and returns everything the robot sent back.
  Outbox raw(std::uint8_t command, const Payload& payload = {}, std::optional<std::uint16_t> to = std::nullopt) {
    next_uid = next_uid == 63 ? 1 : next_uid + 1;
    const std::uint16_t target = to.value_or(id());
    const Message m{protocol::Identifier{target, command, target == 0 ? std::uint8_t{0} : next_uid,
                                         ResponseCode::accepted},
                    payload};
    return model.handle(m, now);
  }
  Outbox send(CommandId c, const Payload& payload = {}, std::optional<std::uint16_t> to = std::nullopt) {
    return raw(protocol::number(c), payload, to);
  }
  // The single reply to a request; fails the test if there is not exactly one.
  Message ask(CommandId c, const Payload& payload = {}) {
    auto out = send(c, payload);
    EXPECT_EQ(out.size(), 1u) << protocol::command_name(c);
    if (out.empty()) return {};
    EXPECT_EQ(out.back().id.command, protocol::number(c));
    EXPECT_EQ(out.back().id.positioner, id());
    return out.back();
  }
  ResponseCode code(CommandId c, const Payload& payload = {}) { return ask(c, payload).id.response; }

  protocol::PositionerStatus status() {
    const auto m = ask(CommandId::get_status);
    return protocol::PositionerStatus::decode(m.payload.span()).value();
  }
  // GET_CURRENT_POSITION in degrees.
  std::pair<double, double> position() {
    const auto m = ask(CommandId::get_current_position);
    const auto p = protocol::ArmPositions::decode(m.payload.span()).value();
    return {p.alpha.degrees(), p.beta.degrees()};
  }
  // Moves time on; collects unsolicited frames.
  void wait(SimDuration d) {
    now += d;
    for (auto& m : model.advance(now)) unsolicited.push_back(m);
  }
  // The sync line high for `hold`, then low again; returns what the robot sent meanwhile (its
  // start reply, when the line was still high at its second look).
  std::vector<Message> sync_pulse(SimDuration hold) {
    std::vector<Message> out;
    for (auto& m : model.set_sync_line(true, now)) out.push_back(m);
    now += hold;
    for (auto& m : model.set_sync_line(false, now)) out.push_back(m);
    return out;
  }
  // Waits in steps until DISPLACEMENT_COMPLETED (or the limit); returns the time waited.
  SimDuration wait_idle(SimDuration limit = 2h, SimDuration step = 100ms) {
    SimDuration waited{};
    while (model.moving() && waited < limit) {
      wait(step);
      waited += step;
    }
    return waited;
  }
};

}  // namespace axon::fps::sim::testing
