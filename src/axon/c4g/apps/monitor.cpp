#include "axon/c4g/apps/monitor.hpp"

#include "axon/c4g/protocol/mode.hpp"

#include <fmt/format.h>

#include <numbers>

namespace axon::c4g::apps {

void MonitorApp::setup(const protocol::InitPacket& init, const protocol::AxisMap& axes) {
  ready_.store(false, std::memory_order_release);
  auto v = make_arm_view(init, axes, 1);
  if (v) arm1_ = std::move(v).value();
  else arm1_.reset();
  ready_.store(true, std::memory_order_release);
}

void MonitorApp::step(const host::CycleContext& ctx, host::ReplyBuilder&) {
  // Mode 0: the safe reply is the answer. Count what the controller does.
  bool on = false;
  for (std::size_t arm = 1; arm <= protocol::kMaxArms; ++arm) on = on || protocol::drives_on(ctx.request.infpar, arm);
  if (on) drives_on_cycles_.fetch_add(1, std::memory_order_relaxed);
  for (const auto& a : ctx.request.open_axes())
    if (a.mode != protocol::code(protocol::Mode::mode0)) {
      non_mode0_cycles_.fetch_add(1, std::memory_order_relaxed);
      break;
    }
}

std::string MonitorApp::status() const {
  std::string out = App::status();
  const std::size_t n = shown_count_.load(std::memory_order_relaxed);
  if (n == 0) return out;
  out += " pos[turns]";
  for (std::size_t i = 0; i < n; ++i) out += fmt::format(" {:.4f}", shown_position_[i].load(std::memory_order_relaxed));
  if (ready_.load(std::memory_order_acquire) && arm1_ && arm1_->first + arm1_->count <= n) {
    protocol::ArmTransform::Vector motor(static_cast<Eigen::Index>(arm1_->count));
    for (std::size_t j = 0; j < arm1_->count; ++j)
      motor[static_cast<Eigen::Index>(j)] = shown_position_[arm1_->first + j].load(std::memory_order_relaxed);
    const auto link = arm1_->transform.link_position(motor);
    out += " arm1[deg]";
    for (Eigen::Index j = 0; j < link.size(); ++j) out += fmt::format(" {:.3f}", link[j] * 180.0 / std::numbers::pi);
  }
  return out;
}

std::string MonitorApp::summary() const {
  return App::summary() + fmt::format("monitor: {} cycles with drives on, {} cycles with an axis outside mode 0\n",
                                      drives_on_cycles(), non_mode0_cycles());
}

}  // namespace axon::c4g::apps
