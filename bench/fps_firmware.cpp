// Firmware upload to the robots of one sextant of the default focal plane (84 robots on 4 buses)
// through their emulated CAN@net gateway over loopback TCP, with the wire model and real-time
// pacing at 1 Mbit/s. The sextant is first powered off and on with the sync line low (what the
// PLC does), so its robots answer from their bootloader; then Array::upgrade_firmware sends the
// image to every robot of the sextant at once (START_FIRMWARE_UPGRADE, 8-byte FIRMWARE_DATA frames
// pipelined per robot, every reply checked, the CRC verdict polled). ratio = achieved / wire time
// of the busiest bus (best of 2 rounds). The image size is FPS_BENCH_IMAGE_KB (default 8 kB).
#include "fps_rig.hpp"

#include "axon/fps/sim/firmware_marker.hpp"

#include <chrono>
#include <cstdio>

using namespace axon;

int main() {
  bench::FpsRig rig;
  rig.start();
  std::size_t kb = 8;
  if (const char* v = std::getenv("FPS_BENCH_IMAGE_KB")) kb = std::strtoul(v, nullptr, 10);
  const auto image = fps::sim::make_firmware_image({4, 2, 0}, kb * 1024).value();
  const int sextant = 1;
  const auto ids = rig.plane.by_sextant().at(sextant);
  rig.in_sim([&] {
    (void)rig.sim->set_positioner_power(sextant, false);
    return rig.sim->set_positioner_power(sextant, true).has_value();
  });
  auto& array = rig.fpa->array();
  fps::host::UpgradeOptions uo;
  uo.verify_poll = std::chrono::milliseconds(5);
  std::size_t failures = 0;
  bench::FpsRig::Round best;
  std::uint64_t frames = 0;
  const bench::FpsRig::Cpu cpu(rig);
  for (int round = 0; round < 2; ++round) {
    const auto r = rig.measure([&] {
      rig.run([&]() -> bench::asio::awaitable<void> {
        auto u = co_await array.upgrade_firmware(ids, image, uo);
        if (!u) {
          std::fprintf(stderr, "upgrade: %s\n", u.error().message().c_str());
          failures = ids.size();
          co_return;
        }
        for (const auto& rr : u.value().robots) {
          if (rr.outcome == fps::host::UpgradeOutcome::ok) continue;
          if (failures++ < 5) std::fprintf(stderr, "robot %u: %s\n", unsigned{rr.id}, rr.reason.c_str());
        }
      });
    });
    frames += r.frames;
    std::printf("round %d: %.3f s, busiest bus %llu frames %.4f s wire (ratio %.2f); %.1f kB/s per bus; simulator "
                "lateness %.2f ms mean, %.1f ms max\n",
                round, r.achieved_s, static_cast<unsigned long long>(r.busiest.frames), r.floor_s, r.ratio(),
                static_cast<double>(image.size()) * static_cast<double>(ids.size()) / 4.0 / r.achieved_s / 1e3,
                r.lateness_ms, std::chrono::duration<double, std::milli>(r.busiest.max_lateness).count());
    if (round == 0 || r.ratio() < best.ratio()) best = r;
  }
  const auto totals = array.client_totals();
  const auto overflows = rig.in_sim([&] { return rig.sim->simulator().receive_overflows(); });
  std::printf("2 rounds: %s, peak RSS %ld kB; %llu timeouts, %llu receive overflows\n", cpu.report(frames).c_str(),
              bench::peak_rss_kb(), static_cast<unsigned long long>(totals.timeouts),
              static_cast<unsigned long long>(overflows));
  rig.stop();
  std::printf("BENCH fps_firmware robots=%zu image_bytes=%zu busiest_frames=%llu failures=%zu floor_s=%.4f "
              "achieved_s=%.4f ratio=%.3f\n",
              ids.size(), image.size(), static_cast<unsigned long long>(best.busiest.frames), failures, best.floor_s,
              best.achieved_s, best.ratio());
  return failures == 0 ? 0 : 1;
}
