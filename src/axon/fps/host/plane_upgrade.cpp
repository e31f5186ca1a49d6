#include "axon/fps/host/plane_upgrade.hpp"
#include "axon/core/clock.hpp"

#include "axon/core/wakeup.hpp"
#include "axon/fps/host/array.hpp"
#include "axon/fps/host/concurrent.hpp"
#include "axon/fps/host/focal_plane_array.hpp"
#include "axon/fps/protocol/firmware_image.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <map>
#include <set>

namespace axon::fps::host {

using protocol::FirmwareVersion;

const char* to_string(PlaneRobotOutcome o) noexcept {
  switch (o) {
    case PlaneRobotOutcome::ok: return "ok";
    case PlaneRobotOutcome::failed: return "failed";
    case PlaneRobotOutcome::not_attempted: return "not-attempted";
  }
  return "?";
}

std::string SextantProgress::to_text() const {
  return fmt::format("sextant {}: {}/{} robots{}{}, {:.2f} MB in {:.1f} s ({:.1f} kB/s){}", sextant, done, total,
                     failed > 0 ? fmt::format(", {} failed", failed) : std::string(), finished ? "" : " so far",
                     static_cast<double>(bytes) / 1e6, seconds, bytes_per_second() / 1e3, finished ? "" : " ...");
}

bool PlaneUpgradeReport::ok() const noexcept {
  return !robots.empty() &&
         std::all_of(robots.begin(), robots.end(), [](const auto& r) { return r.outcome == PlaneRobotOutcome::ok; });
}

std::vector<std::uint16_t> PlaneUpgradeReport::with(PlaneRobotOutcome o) const {
  std::vector<std::uint16_t> out;
  for (const auto& r : robots)
    if (r.outcome == o) out.push_back(r.id);
  return out;
}

const PlaneRobotReport* PlaneUpgradeReport::find(std::uint16_t id) const noexcept {
  auto it = std::find_if(robots.begin(), robots.end(), [&](const auto& r) { return r.id == id; });
  return it == robots.end() ? nullptr : &*it;
}

std::string PlaneUpgradeReport::summary() const {
  std::string out = fmt::format("image {} bytes, CRC-32 0x{:08X}: {} ok, {} failed, {} not attempted\n", size, crc32,
                                with(PlaneRobotOutcome::ok).size(), with(PlaneRobotOutcome::failed).size(),
                                with(PlaneRobotOutcome::not_attempted).size());
  for (const auto& s : sextants) out += "  " + s.to_text() + "\n";
  for (const auto& n : notes) out += "  note: " + n + "\n";
  if (cold) {
    // The policy's own report, indented under its heading.
    out += "  cold policy re-applied after the power cycles:\n";
    const std::string text = cold->to_text();
    std::size_t from = 0;
    while (from < text.size()) {
      const auto nl = text.find('\n', from);
      out += "    " + text.substr(from, nl == std::string::npos ? std::string::npos : nl - from) + "\n";
      if (nl == std::string::npos) break;
      from = nl + 1;
    }
  }
  for (const auto& r : robots) {
    const std::string after = r.after ? r.after->to_string() : std::string("no answer");
    out += fmt::format("  positioner {} (sextant {}): {}, {} attempt{}, runs {}{}{}{}\n", r.id, r.sextant,
                       to_string(r.outcome), r.attempts, r.attempts == 1 ? "" : "s", after,
                       r.reason.empty() ? "" : ": ", r.reason,
                       r.half_written ? " [HALF-WRITTEN: partial image left unused; upgrade it again]" : "");
  }
  return out;
}

namespace {

using Clock = std::chrono::steady_clock;
using Versions = std::map<std::uint16_t, Result<FirmwareVersion>>;

std::string describe(const Result<FirmwareVersion>& v) {
  if (!v) return v.error().message();
  return v.value().is_bootloader() ? fmt::format("bootloader {}", v.value().to_string())
                                   : fmt::format("application {}", v.value().to_string());
}

// GET_FIRMWARE_VERSION of every listed robot at once.
asio::awaitable<Versions> read_versions(Array& array, std::vector<std::uint16_t> ids) {
  std::vector<Result<FirmwareVersion>> got(ids.size(), Result<FirmwareVersion>(Error(HostErrc::cancelled)));
  co_await for_each_concurrently(ids.size(), [&](std::size_t i) -> asio::awaitable<void> {
    Positioner* p = array.find(ids[i]);
    if (p == nullptr) {
      got[i] = Error(HostErrc::unknown_positioner, fmt::format("positioner {}", ids[i]));
      co_return;
    }
    auto v = co_await p->read_firmware_version();
    got[i] = std::move(v);
  });
  Versions out;
  for (std::size_t i = 0; i < ids.size(); ++i) out.emplace(ids[i], std::move(got[i]));
  co_return out;
}

// Reads until every robot answers from the bootloader (or from the application), or `wait` passed.
asio::awaitable<Versions> wait_versions(Array& array, std::vector<std::uint16_t> ids, bool bootloader,
                                        core::Duration wait, core::Duration poll) {
  const auto deadline = Clock::now() + wait;
  Versions last;
  std::vector<std::uint16_t> left = ids;
  for (;;) {
    auto got = co_await read_versions(array, left);
    std::vector<std::uint16_t> still;
    for (auto& [id, v] : got) {
      const bool there = v && v.value().is_bootloader() == bootloader;
      if (!there) still.push_back(id);
      last.insert_or_assign(id, std::move(v));
    }
    left = std::move(still);
    if (left.empty() || Clock::now() >= deadline) co_return last;
    co_await core::sleep_for(poll);
  }
}

struct Run {
  FocalPlaneArray* fpa = nullptr;
  Array* array = nullptr;
  plc::AsyncPlc* plc = nullptr;
  std::span<const std::uint8_t> image;
  const PlaneUpgradeOptions* options = nullptr;
  PlaneUpgradeReport* report = nullptr;
  std::map<std::uint16_t, std::size_t> index;  // id -> report.robots
  std::optional<std::string> plc_failure;      // set once the PLC failed: nothing more is switched

  PlaneRobotReport& robot(std::uint16_t id) { return report->robots[index.at(id)]; }
};

// Power-cycles a sextant: TRAJECTORY_ABORT everywhere, power off, sync line low, pause, (sync high
// for the application), power on, wait for the robots, sync line low. Returns what each answered.
asio::awaitable<Result<Versions>> power_cycle(Run& run, int sextant, std::vector<std::uint16_t> ids, bool bootloader) {
  const auto& o = *run.options;
  auto aborted = co_await run.array->stop_all(false);
  if (!aborted) {
    run.report->notes.push_back(fmt::format("sextant {}: TRAJECTORY_ABORT before switching power: {}", sextant,
                                            aborted.error().message()));
  }
  const plc::Relay sync{plc::RelayKind::sync_line, 0};
  auto off = co_await run.plc->set_positioner_power(sextant, false);
  if (!off) co_return Error(off.error().code, fmt::format("PLC: power off sextant {}: {}", sextant, off.error().message()));
  auto low = co_await run.plc->set_relay(sync, false);
  if (!low) co_return Error(low.error().code, fmt::format("PLC: sync line low: {}", low.error().message()));
  co_await core::sleep_for(o.power_off_time);
  if (!bootloader) {
    auto high = co_await run.plc->set_relay(sync, true);
    if (!high) co_return Error(high.error().code, fmt::format("PLC: sync line high: {}", high.error().message()));
  }
  auto on = co_await run.plc->set_positioner_power(sextant, true);
  if (!on) {
    auto back = co_await run.plc->set_relay(sync, false);
    (void)back;
    co_return Error(on.error().code, fmt::format("PLC: power on sextant {}: {}", sextant, on.error().message()));
  }
  const core::Duration wait = bootloader ? o.bootloader_wait : o.boot_wait;
  auto versions = co_await wait_versions(*run.array, ids, bootloader, wait, o.poll);
  if (!bootloader) {
    auto back = co_await run.plc->set_relay(sync, false);
    if (!back) co_return Error(back.error().code, fmt::format("PLC: sync line low again: {}", back.error().message()));
  }
  co_return versions;
}

std::uint64_t bytes_of(std::size_t chunks, std::uint32_t size) {
  return std::min<std::uint64_t>(std::uint64_t{chunks} * 8, size);
}

asio::awaitable<void> upgrade_sextant(Run& run, int sextant, std::vector<std::uint16_t> ids) {
  const auto& o = *run.options;
  const auto started = Clock::now();
  SextantProgress prog;
  prog.sextant = sextant;
  prog.total = ids.size();
  auto finish = [&] {
    prog.finished = true;
    prog.seconds = core::seconds_since(started);
    prog.done = 0;
    prog.failed = 0;
    for (auto id : ids) {
      if (run.robot(id).outcome == PlaneRobotOutcome::ok) {
        ++prog.done;
      } else {
        ++prog.failed;
      }
    }
    run.report->sextants.push_back(prog);
    if (o.progress) o.progress(prog);
  };
  if (run.plc_failure) {
    for (auto id : ids) run.robot(id).reason = fmt::format("not reached: {}", *run.plc_failure);
    finish();
    co_return;
  }

  // What they run before.
  auto before = co_await read_versions(*run.array, ids);
  for (auto& [id, v] : before) {
    if (v && !v.value().is_bootloader()) run.robot(id).before = v.value();
  }

  // Into the bootloader.
  auto boot = co_await power_cycle(run, sextant, ids, true);
  if (!boot) {
    run.plc_failure = boot.error().message();
    run.report->notes.push_back(fmt::format("sextant {}: {}; the sextant may be left without power", sextant,
                                            boot.error().message()));
    for (auto id : ids) run.robot(id).reason = fmt::format("not attempted: {}", boot.error().message());
    finish();
    co_return;
  }
  std::vector<std::uint16_t> pending;
  for (auto& [id, v] : boot.value()) {
    if (v && v.value().is_bootloader()) {
      pending.push_back(id);
    } else {
      run.robot(id).reason =
          fmt::format("did not come up in the bootloader after power-up with the sync line low ({})", describe(v));
    }
  }

  // Transfers, with retries. Progress counts every attempt's bytes.
  std::map<std::uint16_t, UpgradeRobotReport> last;
  std::map<std::uint16_t, std::string> first_failure;
  std::uint64_t bytes_done = 0;
  std::set<std::uint16_t> transferred;
  const std::uint32_t size = run.report->size;
  for (unsigned attempt = 1; attempt <= 1 + o.retries && !pending.empty(); ++attempt) {
    if (attempt > 1) {
      // A failed robot may have left its bootloader (10 s without a valid command).
      auto now = co_await read_versions(*run.array, pending);
      bool out = false;
      for (auto& [id, v] : now) out = out || !(v && v.value().is_bootloader());
      if (out) {
        spdlog::info("fps plane upgrade: sextant {}: power cycle into the bootloader again for the retry", sextant);
        auto again = co_await power_cycle(run, sextant, ids, true);
        if (!again) {
          run.plc_failure = again.error().message();
          run.report->notes.push_back(fmt::format("sextant {}: retry: {}", sextant, again.error().message()));
          break;
        }
        now = std::move(again).value();
      }
      std::vector<std::uint16_t> ready;
      for (auto id : pending) {
        auto it = now.find(id);
        if (it != now.end() && it->second && it->second.value().is_bootloader()) {
          ready.push_back(id);
        } else {
          last[id].reason += fmt::format("; no retry: not in the bootloader ({})",
                                         it == now.end() ? std::string("not read") : describe(it->second));
        }
      }
      pending = std::move(ready);
      if (pending.empty()) break;
    }
    std::map<std::uint16_t, std::size_t> acked;
    auto last_call = Clock::now();
    UpgradeOptions t = o.transfer;
    t.progress = [&](const UpgradeProgress& p) {
      if (o.transfer.progress) o.transfer.progress(p);
      acked[p.positioner] = p.chunks_acked;
      if (!o.progress || o.progress_interval <= core::Duration::zero()) return;
      if (Clock::now() - last_call < o.progress_interval) return;
      last_call = Clock::now();
      SextantProgress now = prog;
      now.bytes = bytes_done;
      now.done = transferred.size();
      for (const auto& [id, n] : acked) {
        now.bytes += bytes_of(n, size);
        now.done += n == p.chunks_total ? 1 : 0;
      }
      now.seconds = core::seconds_since(started);
      o.progress(now);
    };
    for (auto id : pending) ++run.robot(id).attempts;
    auto r = co_await run.array->upgrade_firmware(pending, run.image, t);
    if (!r) {
      for (auto id : pending) last[id].reason = r.error().message();
      break;
    }
    std::vector<std::uint16_t> failed;
    for (const auto& rr : r.value().robots) {
      bytes_done += bytes_of(rr.chunks_acked, size);
      last[rr.id] = rr;
      if (rr.outcome == UpgradeOutcome::ok) {
        transferred.insert(rr.id);
        continue;
      }
      failed.push_back(rr.id);
      if (!first_failure.contains(rr.id)) first_failure[rr.id] = rr.reason;
      spdlog::warn("fps plane upgrade: positioner {} attempt {}: {}", rr.id, attempt, rr.reason);
    }
    pending = std::move(failed);
  }
  prog.bytes = bytes_done;

  // Back into the application, and what each runs now.
  Versions after;
  if (!run.plc_failure) {
    auto app = co_await power_cycle(run, sextant, ids, false);
    if (!app) {
      run.plc_failure = app.error().message();
      run.report->notes.push_back(fmt::format("sextant {}: back to the application: {}", sextant, app.error().message()));
    } else {
      after = std::move(app).value();
    }
  }
  for (auto id : ids) {
    auto& rep = run.robot(id);
    auto it = after.find(id);
    if (it != after.end() && it->second) rep.after = it->second.value();
    if (rep.attempts == 0) continue;  // not_attempted, reason set above
    const auto& tr = last[id];
    rep.half_written = tr.outcome != UpgradeOutcome::ok && tr.half_written;
    const std::string first = first_failure.contains(id) ? first_failure[id] : std::string();
    if (tr.outcome != UpgradeOutcome::ok) {
      rep.outcome = PlaneRobotOutcome::failed;
      rep.reason = fmt::format("failed after {} attempt{}: {}", rep.attempts, rep.attempts == 1 ? "" : "s", tr.reason);
      if (rep.half_written) rep.reason += "; the robot keeps its previous firmware";
      continue;
    }
    std::string why;
    if (run.plc_failure && after.empty()) {
      why = "image verified by the bootloader, but the sextant could not be powered back into the application";
    } else if (!rep.after) {
      why = fmt::format("image verified by the bootloader, but no answer after power-up ({})",
                        it == after.end() ? std::string("not read") : describe(it->second));
    } else if (rep.after->is_bootloader()) {
      why = "image verified by the bootloader, but the robot stayed in the bootloader after power-up with the sync line high";
    } else if (o.expected_version && *rep.after != *o.expected_version) {
      why = fmt::format("runs {} after the upgrade, expected {}", rep.after->to_string(), o.expected_version->to_string());
    }
    if (!why.empty()) {
      rep.outcome = PlaneRobotOutcome::failed;
      rep.reason = why;
      continue;
    }
    rep.outcome = PlaneRobotOutcome::ok;
    rep.reason = tr.reason;  // e.g. replies lost but the image verified
    if (rep.attempts > 1) {
      rep.reason = fmt::format("ok on attempt {} (first attempt: {}){}", rep.attempts, first,
                               tr.reason.empty() ? "" : "; " + tr.reason);
    }
    if (!o.expected_version && rep.reason.empty()) rep.reason = "version not checked (none expected)";
  }
  finish();
}

}  // namespace

asio::awaitable<Result<PlaneUpgradeReport>> upgrade_plane(FocalPlaneArray& plane, std::span<const std::uint8_t> image,
                                                          PlaneUpgradeOptions options) {
  if (plane.plc() == nullptr)
    co_return Error(HostErrc::invalid_argument, "a focal plane upgrade needs the PLC (no PLC endpoint given)");
  auto img = protocol::FirmwareImage::make(image);
  if (!img) co_return img.error();
  Array& array = plane.array();
  const auto by_sextant = plane.plane().by_sextant();
  const auto known_ids = array.ids();
  const std::set<std::uint16_t> known(known_ids.begin(), known_ids.end());
  std::map<int, std::vector<std::uint16_t>> work;
  for (const auto& [s, ids] : by_sextant) {
    for (auto id : ids)
      if (known.contains(id)) work[s].push_back(id);
  }
  std::vector<int> sextants = options.sextants;
  if (sextants.empty()) {
    for (const auto& [s, ids] : work)
      if (s >= 1) sextants.push_back(s);
  }
  if (sextants.empty()) co_return Error(HostErrc::invalid_argument, "no robots in any sextant to upgrade");
  for (int s : sextants) {
    if (s < 1 || s > plc::kSextants || !work.contains(s))
      co_return Error(HostErrc::invalid_argument, fmt::format("sextant {} has no robots in layout '{}'", s, plane.plane().name()));
  }

  PlaneUpgradeReport report;
  report.size = img.value().header().size;
  report.crc32 = img.value().header().crc32;
  Run run;
  run.fpa = &plane;
  run.array = &array;
  run.plc = plane.plc();
  run.image = image;
  run.options = &options;
  run.report = &report;
  for (int s : sextants) {
    for (auto id : work[s]) {
      PlaneRobotReport r;
      r.id = id;
      r.sextant = s;
      run.index[id] = report.robots.size();
      report.robots.push_back(r);
    }
  }
  for (int s : sextants) {
    spdlog::info("fps plane upgrade: sextant {}: {} robots", s, work[s].size());
    co_await upgrade_sextant(run, s, work[s]);
  }
  if (options.reapply_cold) {
    // The robots came back with the firmware's default speed and holding current.
    ColdControl cold(plane, options.cold_policy);
    auto applied = co_await cold.step(true);
    if (applied) {
      report.cold = std::move(applied).value();
    } else {
      report.notes.push_back("cold policy not re-applied after the upgrade: " + applied.error().message() +
                             "; run `axon fps plane cold`");
    }
  }
  co_return report;
}

}  // namespace axon::fps::host
