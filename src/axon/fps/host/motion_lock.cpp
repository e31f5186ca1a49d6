#include "axon/fps/host/motion_lock.hpp"

#include "axon/fps/host/error.hpp"

#include <fmt/format.h>

namespace axon::fps::host {

Result<void> MotionLock::admit(protocol::CommandId command, std::uint16_t positioner) const {
  const auto& info = protocol::command_info(command);
  if (!state_.locked || !info.moves) return ok();
  ++refused_;
  const std::string to = positioner == 0 ? std::string("broadcast") : fmt::format("positioner {}", positioner);
  return Error(HostErrc::locked, fmt::format("{}: {}; {} not sent", to, state_.reason, info.name));
}

Error MotionLock::interrupted(std::uint16_t positioner) const {
  return Error(HostErrc::locked, fmt::format("positioner {}: {}", positioner, state_.reason));
}

bool MotionLock::lock(std::string reason) {
  if (state_.locked) return false;
  state_.locked = true;
  state_.reason = std::move(reason);
  return true;
}

}  // namespace axon::fps::host
