#include "axon/c4g/apps/law_app.hpp"

#include "axon/c4g/protocol/mode.hpp"

namespace axon::c4g::apps {

using protocol::code;
using protocol::Mode;

namespace {

std::string_view law_mode_text(int mode) noexcept {
  switch (mode) {
    case 1: return "1";
    case 2: return "2";
    case 4: return "4";
    case 5: return "5";
    case 7: return "7";
    case 8: return "8";
    default: return "9";
  }
}

OpenModeApp::Style law_style(const LawOptions& o, std::string name) {
  const bool loops = o.mode == 1 || o.mode == 2;
  return {.app = std::move(name), .waiting = "waiting for the mode", .running = "running", .mode = law_mode_text(o.mode),
          .ramp_s = o.ramp_s, .rearm = o.rearm, .exiting_runs = loops || o.mode == 4 || o.mode == 5,
          .pc_closes_loops = loops};
}

// The standby code of a mode the arm passes through on its way out (0: none kept here).
std::int32_t standby_of(int mode) noexcept {
  switch (mode) {
    case 1: return code(Mode::mode1_standby);
    case 2: return code(Mode::mode2_standby);
    case 4: return code(Mode::mode4_standby);
    case 5: return code(Mode::mode5_standby);
    default: return -1;
  }
}

}  // namespace

LawApp::LawApp(LawOptions options, Law law, std::string name)
    : OpenModeApp(law_style(options, name)), options_(options), law_(std::move(law)), name_(std::move(name)) {
  const int m = options_.mode;
  if (m != 1 && m != 2 && m != 4 && m != 5 && m != 7 && m != 8 && m != 9)
    throw Exception(Error(CoreErrc::invalid_argument, "law: the mode must be 1, 2, 4, 5, 7, 8 or 9"));
  if (!law_) throw Exception(Error(CoreErrc::invalid_argument, "law: no control law"));
  if (options_.ramp_s < 0 || options_.open_time_s < 0 || options_.settle_s < 0)
    throw Exception(Error(CoreErrc::invalid_argument, "law: times must not be negative"));
}

void LawApp::setup(const protocol::InitPacket& init, const protocol::AxisMap& axes) {
  if (!begin_setup()) return;
  auto v = make_arm_view(init, axes, options_.arm);
  if (!v) return refuse("%s: %s", name_.c_str(), v.error().detail.c_str());
  view_ = std::move(v).value();
}

void LawApp::silence() noexcept {
  const Phase p = phase();
  if (p != Phase::waiting && p != Phase::done && p != Phase::refused) refuse("%s: packets stopped during the run", name_.c_str());
}

void LawApp::schedule() noexcept {
  const double period = view_->period_s;
  const double t = advance(period);
  const bool pc_ends = options_.mode != 2;  // mode 2 is the controller's to end
  if (phase() == Phase::running && pc_ends && (stop_requested() || (options_.open_time_s > 0 && t >= options_.open_time_s))) {
    start_fade();
    settled_s_ = 0;
  }
  envelope().step(period);
  if (phase() != Phase::fading || !envelope().faded()) return;
  settled_s_ += period;
  if (settled_s_ >= options_.settle_s) set_phase(Phase::exiting);
}

void LawApp::step(const host::CycleContext& ctx, host::ReplyBuilder& reply) {
  if (!view_) return;
  const std::int32_t mode = options_.mode;
  Gate g = gate_for(ctx.request, view_->first, view_->count, mode);
  if (!g.present) return;
  const std::int32_t standby = standby_of(mode);
  g.inside = g.entered || (standby >= 0 && g.first_mode == standby);
  const Turn turned = turn(g, reply, view_->arm);
  if (turned == Turn::skip) return;
  if (turned == Turn::start) started();
  const bool loops = style().pc_closes_loops;
  const bool switching =
      loops && ctx.switching != nullptr && ctx.switching->axis(view_->first).interval != protocol::SwitchInterval::done;
  const bool first = turned == Turn::start;
  if (g.entered && !switching) schedule();
  const Phase p = phase();
  const LawCycle cycle{ctx, *view_, run_time(), envelope().level(), first, switching, p == Phase::fading || p == Phase::exiting};
  law_(cycle, reply);
  if (phase() == Phase::exiting && g.entered) exit_from_open(reply, view_->arm);
}

}  // namespace axon::c4g::apps
