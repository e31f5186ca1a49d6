#include "axon/c4g/apps/contribute.hpp"

#include "axon/c4g/protocol/mode.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace axon::c4g::apps {

using protocol::code;
using protocol::Mode;

namespace {
OpenModeApp::Style contribute_style(const ContributeOptions& o) {
  return {.app = "contribute", .waiting = "waiting for the mode", .running = "running", .mode = o.mode == 8 ? "8" : "9",
          .ramp_s = o.ramp_s};
}
}  // namespace

ContributeApp::ContributeApp(ContributeOptions options) : OpenModeApp(contribute_style(options)), options_(std::move(options)) {
  for (auto& a : last_) a.store(0, std::memory_order_relaxed);
  for (auto& a : peak_) a.store(0, std::memory_order_relaxed);
  if (options_.mode != 8 && options_.mode != 9)
    throw Exception(Error(CoreErrc::invalid_argument, "contribute: --mode must be 8 (velocity) or 9 (current)"));
  if (options_.amplitude.empty()) throw Exception(Error(CoreErrc::invalid_argument, "contribute: give --amplitude"));
  if (options_.ramp_s < 0 || options_.open_time_s < 0)
    throw Exception(Error(CoreErrc::invalid_argument, "contribute: times must not be negative"));
  for (double v : options_.amplitude)
    if (!std::isfinite(v)) throw Exception(Error(CoreErrc::invalid_argument, "contribute: amplitudes must be finite"));
  for (std::size_t j = 0; j < options_.amplitude.size() && options_.mode == 8; ++j)
    if (!(std::fabs(options_.amplitude[j]) <= options_.max_motor_speed))
      throw Exception(Error(CoreErrc::invalid_argument,
                            fmt::format("contribute: a velocity amplitude of {:g} motor turns/s on axis {} exceeds "
                                        "--max-motor-speed {:g}", options_.amplitude[j], j + 1, options_.max_motor_speed)));
}

void ContributeApp::setup(const protocol::InitPacket& init, const protocol::AxisMap& axes) {
  if (!begin_setup()) return;
  count_ = std::min(axes.arm_count(options_.arm), protocol::kAxesPerArm);
  first_ = axes.arm_first(options_.arm);
  period_s_ = init.period_ms > 0 ? init.period_ms * 1e-3 : 0.002;
  if (count_ == 0) return refuse("contribute: arm %zu has no open axes", options_.arm);
  sine_.configure(options_.amplitude, options_.frequency_hz, count_);
}

void ContributeApp::step(const host::CycleContext& ctx, host::ReplyBuilder& reply) {
  const std::int32_t mode = options_.mode == 8 ? code(Mode::mode8) : code(Mode::mode9);
  const Turn turned = turn(gate_for(ctx.request, first_, count_, mode), reply, options_.arm);
  if (turned == Turn::skip) return;
  if (turned == Turn::start) started();
  const double t = advance(period_s_);
  if (phase() == Phase::running && (stop_requested() || (options_.open_time_s > 0 && t >= options_.open_time_s)))
    start_fade();
  const double env = envelope().step(period_s_);
  if (envelope().faded()) set_phase(Phase::exiting);
  for (std::size_t j = 0; j < count_; ++j) {
    const double v = env * sine_.value(j, t);
    auto& ax = reply.axis(first_ + j);
    if (options_.mode == 8) ax.d4 = static_cast<float>(v * period_s_);  // turns/s -> turns per cycle
    else ax.d5 = static_cast<float>(v);
    last_[j].store(v, std::memory_order_relaxed);
    if (std::fabs(v) > peak_[j].load(std::memory_order_relaxed)) peak_[j].store(std::fabs(v), std::memory_order_relaxed);
  }
  if (phase() == Phase::exiting) exit_from_open(reply, options_.arm);
}

std::string ContributeApp::note_text(std::int32_t c) const {
  switch (c) {
    case kNoteStarted:
      return fmt::format("contribute: {} contribution started (mode {}, arm {})", options_.mode == 8 ? "velocity" : "current",
                         options_.mode, options_.arm);
    case kNoteFading: return "contribute: fading the contribution out";
    default: return OpenModeApp::note_text(c);
  }
}

std::string ContributeApp::status() const {
  std::string out = OpenModeApp::status() + (options_.mode == 8 ? " velocity[turns/s]" : " current[A]");
  for (std::size_t j = 0; j < 6; ++j) out += fmt::format(" {:.3f}", last(j));
  return out;
}

std::string ContributeApp::summary() const {
  std::string out = App::summary() + fmt::format("contribute: mode {}, {:.3f} s, phase {}, peak per axis", options_.mode,
                                                 elapsed_s(), to_string(phase()));
  for (std::size_t j = 0; j < 6; ++j) out += fmt::format(" {:.3f}", peak(j));
  return out + (options_.mode == 8 ? " turns/s\n" : " A\n");
}

}  // namespace axon::c4g::apps
