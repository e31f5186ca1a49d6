#include "axon/fps/host/status_table.hpp"

#include <fmt/format.h>

#include <algorithm>

namespace axon::fps::host {

std::string StatusRow::state() const {
  if (in_bootloader()) return "bootloader";
  if (!status) return error.empty() ? "unknown" : "no-reply";
  if (status->collided()) return "collision";
  if (status->calibrating()) return "calibrating";
  if (!status->idle()) return "moving";
  if (!status->initialized()) return "no-datum";
  return "ready";
}

const StatusRow* StatusTable::find(std::uint16_t id) const noexcept {
  auto it = std::find_if(rows.begin(), rows.end(), [&](const StatusRow& r) { return r.id == id; });
  return it == rows.end() ? nullptr : &*it;
}

std::size_t StatusTable::count_ready() const noexcept {
  return static_cast<std::size_t>(std::count_if(rows.begin(), rows.end(), [](const StatusRow& r) { return r.ready(); }));
}

std::string StatusTable::to_text() const {
  std::string out = fmt::format("{:>5}  {:<10} {:<9} {:<11} {:>10} {:>10}  {:<18} {}\n", "id", "bus", "firmware",
                                "state", "alpha", "beta", "status", "flags / error");
  for (const auto& r : rows) {
    const std::string fw = r.firmware ? r.firmware->to_string() : "-";
    const std::string a = r.position ? fmt::format("{:.3f}", r.position->alpha) : "-";
    const std::string b = r.position ? fmt::format("{:.3f}", r.position->beta) : "-";
    std::string raw = "-", flags;
    if (r.status) {
      raw = fmt::format("0x{:016X}", r.status->raw());
      flags = r.status->to_string();
    } else if (r.bootloader_status) {
      raw = fmt::format("0x{:08X}", r.bootloader_status->raw());
      flags = r.bootloader_status->to_string();
    }
    if (!r.error.empty()) flags = flags.empty() ? r.error : flags + "; " + r.error;
    out += fmt::format("{:>5}  {:<10} {:<9} {:<11} {:>10} {:>10}  {:<18} {}\n", r.id, r.bus_name, fw, r.state(), a, b,
                       raw, flags);
  }
  return out;
}

}  // namespace axon::fps::host
