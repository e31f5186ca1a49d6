#include "axon/fps/protocol/commands.hpp"

#include "axon/fps/protocol/error.hpp"
#include "axon/fps/protocol/names.hpp"

#include <fmt/format.h>

#include <cctype>

namespace axon::fps::protocol {
namespace {

constexpr bool table_sorted_and_unique() {
  for (std::size_t i = 1; i < kCommands.size(); ++i) {
    if (kCommands[i - 1].number() >= kCommands[i].number()) return false;
  }
  return true;
}
static_assert(table_sorted_and_unique(), "command table must be sorted by number without duplicates");
static_assert(kCommands.size() == 66, "5 bootloader-only or shared commands plus the application table");

constexpr bool layouts_consistent() {
  for (const auto& c : kCommands) {
    for (const Layout* l : {&c.request, &c.reply, &c.bootloader_reply}) {
      if (l->min_size > l->max_size || l->max_size > 8) return false;
      if (l->is_fixed()) {
        std::size_t sum = 0;
        for (std::size_t i = 0; i < l->field_count; ++i) sum += field_width(l->fields[i].type);
        if (sum != l->max_size) return false;
      }
    }
    if (!c.bootloader && !c.application) return false;
  }
  return true;
}
static_assert(layouts_consistent(), "every fixed layout's fields must add up to its size");

constexpr bool safety_classes_consistent() {
  for (const auto& c : kCommands) {
    if (c.moves && c.read_only) return false;
    if (!c.host_sends && (c.moves || c.read_only)) return false;
  }
  return true;
}
static_assert(safety_classes_consistent(), "a command moves or only reads, not both; robot-sent frames have no class");

}  // namespace

Result<const CommandInfo*> lookup_command(std::uint8_t number) {
  if (const auto* c = find_command(number)) return c;
  return Error(ProtocolErrc::unknown_command, fmt::format("command {}", number));
}

const CommandInfo* find_command(std::string_view name) noexcept {
  for (const auto& c : kCommands) {
    if (iequals(c.name, name)) return &c;
  }
  return nullptr;
}

std::string command_name(std::uint8_t number) {
  if (const auto* c = find_command(number)) return std::string(c->name);
  return fmt::format("UNKNOWN_COMMAND_{}", number);
}

Result<void> check_request(const CommandInfo& c, bool broadcast, std::size_t size, std::optional<Mode> mode) {
  if (!c.host_sends) {
    return Error(ProtocolErrc::not_sendable, fmt::format("{} ({})", c.name, c.number()));
  }
  if (mode && !c.valid_in(*mode)) {
    return Error(ProtocolErrc::wrong_mode,
                 fmt::format("{} ({}) is not taken by the {}", c.name, c.number(),
                             *mode == Mode::bootloader ? "bootloader" : "main application"));
  }
  if (broadcast && !c.broadcast) {
    return Error(ProtocolErrc::broadcast_not_allowed, fmt::format("{} ({})", c.name, c.number()));
  }
  if (!c.request.accepts(size)) {
    return Error(ProtocolErrc::wrong_length, fmt::format("{} request: {} data bytes, expected {}..{}", c.name, size,
                                                         c.request.min_size, c.request.max_size));
  }
  return ok();
}

Result<void> check_reply(const CommandInfo& c, Mode mode, ResponseCode code, std::size_t size) {
  const auto& l = c.reply_in(mode);
  if (l.accepts(size)) return ok();
  if (code != ResponseCode::accepted && size == 0) return ok();
  return Error(ProtocolErrc::wrong_length, fmt::format("{} reply ({}): {} data bytes, expected {}..{}", c.name,
                                                       response_name(code), size, l.min_size, l.max_size));
}

RequestVerdict check_device_request(std::uint8_t number, Mode mode, bool broadcast, std::size_t size,
                                    const DeviceOptions& options) noexcept {
  const CommandInfo* c = find_command(number);
  if (c == nullptr) return {ResponseCode::unknown_command, nullptr};
  if (options.get_holding_current_on_112 && c->id == CommandId::set_holding_current && size == 0) {
    c = &command_info(CommandId::get_holding_current);
  }
  if (!c->valid_in(mode) || !c->host_sends) {
    return {mode == Mode::bootloader ? ResponseCode::invalid_bootloader_command : ResponseCode::invalid_command, c};
  }
  if (broadcast && !c->broadcast) return {ResponseCode::invalid_broadcast, c};
  if (!c->request.accepts(size)) return {ResponseCode::incorrect_data_length, c};
  return {ResponseCode::accepted, c};
}

}  // namespace axon::fps::protocol
