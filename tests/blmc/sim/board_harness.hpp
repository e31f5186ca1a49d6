// A board driven by hand in tests: frames in as command text or IqRef values, time moved in whole
// milliseconds, everything the board sent decoded with the protocol codec.
#pragma once

#include "axon/blmc/protocol/command.hpp"
#include "axon/blmc/protocol/frames.hpp"
#include "axon/blmc/sim/board.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <string_view>
#include <vector>

namespace axon::blmc::sim::test {

using namespace std::chrono_literals;

struct Sent {
  BoardTime at;
  protocol::FromBoard msg;
};

struct BoardHarness {
  explicit BoardHarness(BoardConfig c = {}, BoardFaultPlan p = {}) : board(std::move(c), std::move(p)) {}

  Board board;
  BoardTime now{0};
  std::vector<Sent> sent;

  void command(std::string_view text) {
    const auto c = protocol::Command::parse(text);
    ASSERT_TRUE(c) << text;
    ASSERT_TRUE(board.receive(protocol::encode(c.value()).value(), now));
  }
  void iq_ref(double m1, double m2 = 0.0) { ASSERT_TRUE(board.receive(protocol::encode_iq_ref({m1, m2}).value(), now)); }
  void pair(protocol::MessageId id, double m1, double m2 = 0.0) {
    ASSERT_TRUE(board.receive(protocol::encode(protocol::PairMessage{id, {m1, m2}}).value(), now));
  }
  // Runs the board until `t` (inclusive) and records what it sent, stamped with the cycle time.
  void run_until(BoardTime t) {
    while (board.next_cycle_time() <= t) {
      const BoardTime at = board.next_cycle_time();
      std::vector<can::Frame> out;
      board.advance(at, out);
      for (const auto& f : out) {
        auto m = protocol::decode_from_board(f);
        ASSERT_TRUE(m) << f.to_string();
        sent.push_back(Sent{at, m.value()});
      }
    }
    now = t;
  }
  void run_for(BoardTime d) { run_until(now + d); }

  // Enables system and motor(s) and waits for the alignment to finish.
  void enable_and_align(bool motor2 = false) {
    command("ENABLE_SYS=1");
    command("ENABLE_MTR1=1");
    if (motor2) command("ENABLE_MTR2=1");
    run_for(board.config().alignment_time + 2ms);
    ASSERT_TRUE(board.status().motor1_ready);
  }

  [[nodiscard]] std::vector<protocol::Status> statuses() const {
    std::vector<protocol::Status> out;
    for (const auto& s : sent)
      if (const auto* st = std::get_if<protocol::Status>(&s.msg)) out.push_back(*st);
    return out;
  }
  [[nodiscard]] std::vector<Sent> of(protocol::MessageId id) const {
    std::vector<Sent> out;
    for (const auto& s : sent) {
      if (const auto* p = std::get_if<protocol::PairMessage>(&s.msg); p && p->id == id) out.push_back(s);
    }
    return out;
  }
};

}  // namespace axon::blmc::sim::test
