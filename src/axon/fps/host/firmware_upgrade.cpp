// Array::upgrade_firmware and its report.
#include "axon/fps/host/firmware_upgrade.hpp"

#include "axon/fps/host/array.hpp"
#include "axon/fps/host/concurrent.hpp"
#include "axon/fps/protocol/firmware_image.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>

namespace axon::fps::host {

using protocol::CommandId;

const char* to_string(UpgradeOutcome o) noexcept {
  switch (o) {
    case UpgradeOutcome::ok: return "ok";
    case UpgradeOutcome::failed: return "failed";
    case UpgradeOutcome::not_attempted: return "not-attempted";
  }
  return "?";
}

bool UpgradeReport::ok() const noexcept {
  return !robots.empty() &&
         std::all_of(robots.begin(), robots.end(), [](const auto& r) { return r.outcome == UpgradeOutcome::ok; });
}

std::vector<std::uint16_t> UpgradeReport::with(UpgradeOutcome o) const {
  std::vector<std::uint16_t> out;
  for (const auto& r : robots) {
    if (r.outcome == o) out.push_back(r.id);
  }
  return out;
}

const UpgradeRobotReport* UpgradeReport::find(std::uint16_t id) const noexcept {
  auto it = std::find_if(robots.begin(), robots.end(), [&](const auto& r) { return r.id == id; });
  return it == robots.end() ? nullptr : &*it;
}

std::string UpgradeReport::summary() const {
  std::string out = fmt::format("image {} bytes, CRC-32 0x{:08X}: {} ok, {} failed, {} not attempted\n", size, crc32,
                                with(UpgradeOutcome::ok).size(), with(UpgradeOutcome::failed).size(),
                                with(UpgradeOutcome::not_attempted).size());
  for (const auto& r : robots) {
    out += fmt::format("  positioner {}: {} ({}/{} chunks){}{}{}\n", r.id, to_string(r.outcome), r.chunks_acked,
                       r.chunks_total, r.reason.empty() ? "" : ": ", r.reason,
                       r.half_written ? " [HALF-WRITTEN: the robot keeps its previous firmware; upgrade it again]" : "");
  }
  return out;
}

asio::awaitable<Result<UpgradeReport>> Array::upgrade_firmware(std::vector<std::uint16_t> ids,
                                                               std::span<const std::uint8_t> image,
                                                               UpgradeOptions options) {
  auto img = protocol::FirmwareImage::make(image);
  if (!img) co_return img.error();
  if (ids.empty()) co_return Error(HostErrc::invalid_argument, "no positioners to upgrade");
  UpgradeReport report;
  report.size = img.value().header().size;
  report.crc32 = img.value().header().crc32;
  std::vector<protocol::Request> chunks;
  chunks.reserve(img.value().chunk_count());
  for (std::size_t i = 0; i < img.value().chunk_count(); ++i) {
    chunks.push_back({CommandId::firmware_data, img.value().chunk(i).encode()});
  }
  for (auto id : ids) {
    UpgradeRobotReport r;
    r.id = id;
    r.chunks_total = chunks.size();
    report.robots.push_back(r);
  }
  co_await for_each_concurrently(ids.size(), [&](std::size_t i) -> asio::awaitable<void> {
    co_await upgrade_one(ids[i], chunks, img.value().header(), options, report.robots[i]);
  });
  spdlog::info("fps firmware upgrade: {}", report.summary());
  co_return report;
}

asio::awaitable<void> Array::upgrade_one(std::uint16_t id, const std::vector<protocol::Request>& chunks,
                                         const protocol::FirmwareUpgradeHeader& header, const UpgradeOptions& options,
                                         UpgradeRobotReport& report) {
  auto skip = [&](std::string why) {
    report.outcome = UpgradeOutcome::not_attempted;
    report.reason = std::move(why);
  };
  auto failed = [&](std::string why) {
    report.outcome = UpgradeOutcome::failed;
    report.reason = std::move(why);
  };
  Positioner* p = find(id);
  if (!p) co_return skip("unknown positioner (run discovery first)");
  auto fw = co_await p->read_firmware_version();
  if (!fw) co_return skip(fw.error().message());
  report.version_before = fw.value();
  if (!fw.value().is_bootloader()) {
    co_return skip(fmt::format("runs firmware {}, not the bootloader; power it up with the sync line low",
                               fw.value().to_string()));
  }
  auto start = co_await p->client().call<CommandId::start_firmware_upgrade>(id, header);
  if (!start) co_return failed(fmt::format("START_FIRMWARE_UPGRADE refused: {}", start.error().message()));

  std::size_t reported = 0;
  auto progress = [&](std::size_t acked) {
    report.chunks_acked = acked;
    if (!options.progress) return;
    if (acked == chunks.size() || acked - reported >= std::max<std::size_t>(options.progress_every, 1)) {
      reported = acked;
      options.progress(UpgradeProgress{id, acked, chunks.size()});
    }
  };
  auto sent = co_await p->client().pipeline(id, chunks, options.window, progress);
  report.chunks_acked = sent.accepted;
  if (!sent.ok()) {
    // A request or only its reply may have been lost, and the frames already in flight went on:
    // ask the robot what it has before saying anything about its state.
    const std::string why = fmt::format("transfer stopped at chunk {} of {}: {}", *sent.failed_index, chunks.size(),
                                        sent.error ? sent.error->message() : std::string("?"));
    auto st = co_await p->read_bootloader_status();
    if (st) {
      report.final_status = st.value();
      if (st.value().upgrade_succeeded()) {
        report.outcome = UpgradeOutcome::ok;
        report.reason = fmt::format("replies were lost ({}), but the robot received and verified the whole image", why);
        co_return;
      }
      if (st.value().upgrade_failed()) {
        co_return failed(fmt::format("{}; the robot's CRC-32 check failed, it keeps its previous firmware", why));
      }
    }
    report.half_written = true;
    co_return failed(why);
  }

  // The bootloader checks the CRC once the last byte is in.
  const auto deadline = std::chrono::steady_clock::now() + options.verify_timeout;
  for (;;) {
    auto st = co_await p->read_bootloader_status();
    if (!st) co_return failed(fmt::format("image sent; verification read failed: {}", st.error().message()));
    report.final_status = st.value();
    if (st.value().upgrade_failed()) {
      co_return failed("image sent, but the robot's CRC-32 check failed; it keeps its previous firmware");
    }
    if (st.value().upgrade_succeeded()) break;
    if (std::chrono::steady_clock::now() >= deadline) {
      co_return failed(fmt::format("image sent, but the robot did not confirm it (status {})", st.value().to_string()));
    }
    co_await core::sleep_for(options.verify_poll);
  }
  report.outcome = UpgradeOutcome::ok;
  report.reason.clear();
}

}  // namespace axon::fps::host
