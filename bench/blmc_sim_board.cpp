// Cost of simulating one blmc board: firmware cycles with both motors aligned and driven and all
// four data messages on, timed in one thread. The baseline is the firmware period itself (1 ms):
// ratio = CPU time per simulated cycle / 1 ms, i.e. the share of one core a board takes in real
// time (transport and socket costs excluded).
#include "axon/blmc/protocol/command.hpp"
#include "axon/blmc/protocol/frames.hpp"
#include "axon/blmc/sim/board.hpp"

#include <fmt/format.h>

#include <chrono>
#include <cstdlib>
#include <vector>

using namespace axon;
using namespace axon::blmc;
using namespace std::chrono_literals;

int main(int argc, char** argv) {
  const long cycles = argc > 1 ? std::atol(argv[1]) : 20000;
  sim::BoardConfig config;
  config.alignment_time = 0ms;
  sim::Board board(config);
  for (const char* text : {"ENABLE_SYS=1", "ENABLE_MTR1=1", "ENABLE_MTR2=1", "SEND_ALL=1"}) {
    if (!board.receive(protocol::encode(protocol::Command::parse(text).value()).value(), 0ms)) return 1;
  }
  std::vector<can::Frame> out;
  out.reserve(64);
  sim::BoardTime t{0};
  std::size_t frames = 0;
  const auto start = std::chrono::steady_clock::now();
  for (long k = 0; k < cycles; ++k) {
    if (k % 10 == 0) {  // a host changing its reference every 10 ms
      const double i = (k / 10) % 2 == 0 ? 0.3 : -0.3;
      (void)board.receive(protocol::encode_iq_ref({i, -i}).value(), t);
    }
    out.clear();
    board.advance(t, out);
    frames += out.size();
    t += sim::kCycle;
  }
  const double elapsed_ns = std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - start).count();
  const double per_cycle = elapsed_ns / static_cast<double>(cycles);
  fmt::print("BENCH blmc_sim_board cycles={} frames={} ns_per_cycle={:.0f} ratio={:.4f}\n", cycles, frames, per_cycle,
             per_cycle / 1e6);
  return 0;
}
