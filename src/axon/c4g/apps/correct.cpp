#include "axon/c4g/apps/correct.hpp"

#include "axon/c4g/protocol/mode.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <numbers>

namespace axon::c4g::apps {

using protocol::code;
using protocol::Mode;

namespace {

OpenModeApp::Style correct_style(const CorrectOptions& o) {
  return {.app = "correct", .waiting = "waiting for mode 7", .running = "correcting", .mode = "7", .ramp_s = o.ramp_s,
          .fade_in = false, .rearm = o.rearm};
}

Exception refused(std::string text) { return Exception(Error(CoreErrc::invalid_argument, std::move(text))); }

// The sine's amplitudes and the file's values within max_abs: checked when the app is built.
void check_sources(const CorrectOptions& o) {
  if (auto v = check_sine("correct", o.amplitude_rad, o.frequency_hz, o.limits); !v) throw Exception(v.error());
  if (!o.values) return;
  const Trajectory& t = *o.values;
  for (std::size_t r = 0; r < t.rows(); ++r)
    for (std::size_t j = 0; j < t.axes(); ++j)
      if (!(std::fabs(t.value(r, j)) <= o.limits.max_abs(j)))
        throw refused(fmt::format("correct: the file's row {} (t={:g} s) asks {:g} deg on axis {}, beyond the correction limit "
                                  "{:g} deg (--max-correction)", r + 1, t.time(r), t.value(r, j) * kRadToDeg, j + 1,
                                  o.limits.max_abs(j) * kRadToDeg));
}
}  // namespace

CorrectApp::CorrectApp(CorrectOptions options) : OpenModeApp(correct_style(options)), options_(std::move(options)) {
  for (auto& a : applied_) a.store(0, std::memory_order_relaxed);
  const int sources = (options_.values ? 1 : 0) + (options_.feed ? 1 : 0) + (options_.amplitude_rad.empty() ? 0 : 1);
  if (sources != 1)
    throw Exception(Error(CoreErrc::invalid_argument, "correct: give exactly one of amplitudes (a sine), a file of values or a live feed"));
  if (!(options_.feed_timeout_s > 0))
    throw Exception(Error(CoreErrc::invalid_argument, "correct: the feed timeout must be positive"));
  if (options_.ramp_s < 0 || options_.open_time_s < 0)
    throw Exception(Error(CoreErrc::invalid_argument, "correct: times must not be negative"));
  if (auto v = validate(options_.limits); !v) throw Exception(v.error());
  check_sources(options_);
}

void CorrectApp::setup(const protocol::InitPacket& init, const protocol::AxisMap& axes) {
  if (!begin_setup()) return;
  auto v = make_arm_view(init, axes, options_.arm);
  if (!v) return refuse("correct: %s", v.error().detail.c_str());
  view_ = std::move(v).value();
  const std::size_t n = view_->count;
  const double period = view_->period_s;
  const double max_step = options_.max_motor_speed * period;
  if (options_.feed) {
    if (options_.feed->axes() != n) {
      fail("correct: the feed sends %zu values, arm %zu has %zu axes", options_.feed->axes(), options_.arm, n);
      set_phase(Phase::refused);
    }
  } else if (options_.values) {
    const Trajectory& f = *options_.values;
    if (f.axes() != n) return refuse("correct: the file has %zu axes, arm %zu has %zu", f.axes(), options_.arm, n);
    // Continuity of the file as it will be played, from a zero correction.
    protocol::ArmTransform::Vector link(static_cast<Eigen::Index>(n)), prev = protocol::ArmTransform::Vector::Zero(static_cast<Eigen::Index>(n));
    const auto rows = static_cast<std::size_t>(std::ceil(f.end_time() / period)) + 1;
    for (std::size_t k = 1; k <= rows; ++k) {
      correction(static_cast<double>(k) * period, 1.0, link);
      const auto step = view_->transform.motor_velocity(link - prev);
      for (std::size_t j = 0; j < n; ++j)
        if (std::fabs(step[static_cast<Eigen::Index>(j)]) > max_step)
          return refuse("correct: the correction is not continuous: axis %zu moves %.4f motor turns in one cycle at "
                        "t=%.3f s (limit %.4f)",
                        j + 1, std::fabs(step[static_cast<Eigen::Index>(j)]), static_cast<double>(k) * period, max_step);
      prev = link;
    }
  } else {
    sine_.configure(options_.amplitude_rad, options_.frequency_hz, n);
    // Peak motor speed: |K_r| times the link peak speeds 2 pi f A (over 2 pi per turn).
    const auto& kr = view_->transform.kr();
    for (std::size_t i = 0; i < n; ++i) {
      double peak = 0;
      for (std::size_t j = 0; j < n; ++j)
        peak += std::fabs(kr(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j))) * std::fabs(sine_.frequency(j) * sine_.amplitude(j));
      if (peak > options_.max_motor_speed)
        return refuse("correct: the sine needs up to %.1f motor turns/s on axis %zu (limit %.1f)", peak, i + 1,
                      options_.max_motor_speed);
    }
  }
  if (!options_.feed && !check_steps(period)) set_phase(Phase::refused);
}

bool CorrectApp::check_steps(double period) noexcept {
  const std::size_t n = view_->count;
  const double fade = fade_per_cycle(period, options_.ramp_s);
  for (std::size_t j = 0; j < n; ++j) {
    double step = 0;  // bound on the change per cycle, link side
    if (options_.values) {
      const Trajectory& f = *options_.values;
      double peak = 0, prev = 0;
      const auto rows = static_cast<std::size_t>(std::ceil(f.end_time() / period)) + 1;
      std::array<double, protocol::kAxesPerArm> pos{}, vel{};
      for (std::size_t k = 1; k <= rows; ++k) {
        f.sample(static_cast<double>(k) * period, std::span<double>(pos.data(), n), std::span<double>(vel.data(), n));
        step = std::max(step, std::fabs(pos[j] - prev));
        peak = std::max(peak, std::fabs(pos[j]));
        prev = pos[j];
      }
      step += peak * fade;
    } else {
      step = sine_step_bound(sine_.amplitude(j), sine_.frequency(j), period, options_.ramp_s);
    }
    if (step > options_.limits.max_step(j) * (1 + 1e-9)) {
      fail("correct: the correction can change by %.4f deg in one cycle on axis %zu (fades included), beyond the limit "
           "%.4f deg per cycle (--max-correction-step)",
           step * kRadToDeg, j + 1, options_.limits.max_step(j) * kRadToDeg);
      return false;
    }
  }
  return true;
}

void CorrectApp::correction(double t, double env, protocol::ArmTransform::Vector& link) const noexcept {
  const std::size_t n = view_->count;
  if (options_.values) {
    std::array<double, protocol::kAxesPerArm> pos{}, vel{};
    options_.values->sample(t, std::span<double>(pos.data(), n), std::span<double>(vel.data(), n));
    for (std::size_t j = 0; j < n; ++j) link[static_cast<Eigen::Index>(j)] = env * pos[j];
  } else {
    for (std::size_t j = 0; j < n; ++j) link[static_cast<Eigen::Index>(j)] = env * sine_.value(j, t);
  }
}

void CorrectApp::take_reading() noexcept {
  if (!options_.feed->latest(incoming_) || incoming_.sequence == seen_sequence_) return;  // torn or nothing new
  seen_sequence_ = incoming_.sequence;
  for (std::size_t j = 0; j < view_->count; ++j) {
    if (std::fabs(incoming_.values[j]) <= options_.limits.max_abs(j)) continue;  // false for NaN too
    refused_axis_.store(static_cast<int>(j), std::memory_order_relaxed);
    refused_value_.store(incoming_.values[j], std::memory_order_relaxed);
    refused_samples_.fetch_add(1, std::memory_order_relaxed);
    if (!refusing_) note(kNoteFeedRefused);
    refusing_ = true;
    return;
  }
  refusing_ = false;
  reading_ = incoming_;
}

void CorrectApp::feed_target(double env, protocol::ArmTransform::Vector& link) noexcept {
  const std::size_t n = view_->count;
  take_reading();
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  const std::int64_t now_ns = static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
  const bool stale = reading_.steady_ns == 0 ||
                     static_cast<double>(now_ns - reading_.steady_ns) > options_.feed_timeout_s * 1e9;
  if (stale != stale_) {
    stale_ = stale;
    if (reading_.steady_ns != 0) note(stale ? kNoteFeedStale : kNoteFeedBack);
  }
  if (stale) stale_cycles_.fetch_add(1, std::memory_order_relaxed);
  for (std::size_t j = 0; j < n; ++j) link[static_cast<Eigen::Index>(j)] = stale ? 0.0 : env * reading_.values[j];
}

void CorrectApp::slew(protocol::ArmTransform::Vector& link) noexcept {
  bool cut = false;
  for (std::size_t j = 0; j < view_->count; ++j) {
    auto& x = link[static_cast<Eigen::Index>(j)];
    const double limit = options_.limits.max_step(j);
    const double step = std::clamp(x - link_last_[j], -limit, limit);
    cut = cut || step != x - link_last_[j];
    x = link_last_[j] + step;
  }
  if (cut) slewed_cycles_.fetch_add(1, std::memory_order_relaxed);
}

int CorrectApp::out_of_bounds(const protocol::ArmTransform::Vector& link) const noexcept {
  for (std::size_t j = 0; j < view_->count; ++j) {
    const double x = link[static_cast<Eigen::Index>(j)];
    // A slewed step may round just above the limit.
    if (!(std::fabs(x) <= options_.limits.max_abs(j)) ||
        !(std::fabs(x - link_last_[j]) <= options_.limits.max_step(j) * (1 + 1e-9)))
      return static_cast<int>(j);
  }
  return -1;
}

void CorrectApp::refuse_now(host::ReplyBuilder& reply) noexcept {
  set_phase(Phase::refused);  // after fail()
  for (std::size_t i = 0; i < view_->count; ++i) reply.axis(view_->first + i).d1 = 0;
  exit_from_open(reply, view_->arm);
}

void CorrectApp::restart() noexcept {
  last_ = {};
  link_last_ = {};
  for (auto& a : applied_) a.store(0, std::memory_order_relaxed);
  started();
}

void CorrectApp::step(const host::CycleContext& ctx, host::ReplyBuilder& reply) {
  if (!view_) return;
  const Turn turned = turn(gate_for(ctx.request, view_->first, view_->count, code(Mode::mode7)), reply, view_->arm);
  if (turned == Turn::skip) return;
  if (turned == Turn::start) restart();
  const double t = advance(view_->period_s);
  if (phase() == Phase::running) {
    const bool file_end = options_.values && t >= options_.values->end_time() && !stop_requested();
    const bool time_up = options_.open_time_s > 0 && t >= options_.open_time_s;
    if (file_end) set_phase(Phase::exiting);
    else if (stop_requested() || time_up) start_fade();
  }
  double env = envelope().step(view_->period_s);
  if (phase() == Phase::exiting) env = 1.0;  // the file's end: its last offset stays applied
  else if (envelope().faded()) set_phase(Phase::exiting);
  emit(env, reply);
}

void CorrectApp::emit(double env, host::ReplyBuilder& reply) noexcept {
  const std::size_t n = view_->count, first = view_->first;
  const double period = view_->period_s;
  protocol::ArmTransform::Vector link(static_cast<Eigen::Index>(n));
  if (options_.feed) {
    feed_target(env, link);
    slew(link);
  } else {
    correction(run_time(), env, link);
  }
  if (const int j = out_of_bounds(link); j >= 0) {
    fail("correct: the correction on axis %d (%.4f deg, %.4f deg since the last cycle) breaks its limits (%.4f deg, "
         "%.4f deg per cycle)", j + 1, link[j] * kRadToDeg, (link[j] - link_last_[static_cast<std::size_t>(j)]) * kRadToDeg,
         options_.limits.max_abs(static_cast<std::size_t>(j)) * kRadToDeg, options_.limits.max_step(static_cast<std::size_t>(j)) * kRadToDeg);
    refuse_now(reply);
    return;
  }
  auto motor = view_->transform.motor_velocity(link);
  const double max_step = options_.max_motor_speed * period;
  if (options_.feed) {
    // Slew towards the sensor's target; the fade ends only once the correction is back at zero.
    bool at_zero = true;
    for (std::size_t j = 0; j < n; ++j) {
      auto& m = motor[static_cast<Eigen::Index>(j)];
      m = last_[j] + std::clamp(m - last_[j], -max_step, max_step);
      at_zero = at_zero && std::fabs(m) < 1e-12;
    }
    if (phase() == Phase::exiting && !at_zero) set_phase(Phase::fading);
  }
  for (std::size_t j = 0; j < n; ++j) {
    const double inc = motor[static_cast<Eigen::Index>(j)] - last_[j];
    if (!(std::fabs(inc) <= max_step * (1 + 1e-9))) {  // a slewed step may round just above the limit
      fail("correct: increment of %.4f motor turns on axis %zu exceeds %.4f", inc, j + 1, max_step);
      refuse_now(reply);
      return;
    }
  }
  for (std::size_t j = 0; j < n; ++j) {
    const double c = motor[static_cast<Eigen::Index>(j)];
    reply.axis(first + j).d1 = static_cast<float>(c - last_[j]);
    applied_[j].store(c, std::memory_order_relaxed);
    last_[j] = c;
    link_last_[j] = link[static_cast<Eigen::Index>(j)];
  }
  if (phase() == Phase::exiting) exit_from_open(reply, view_->arm);
}

std::string CorrectApp::note_text(std::int32_t c) const {
  switch (c) {
    case kNoteStarted: return fmt::format("correct: correction started (mode 7, arm {})", options_.arm);
    case kNoteFading: return "correct: fading the correction out";
    case kNoteFeedStale:
      return fmt::format("correct: no feed values for {:.0f} ms: correction returning to zero", options_.feed_timeout_s * 1e3);
    case kNoteFeedBack: return "correct: feed values again";
    case kNoteFeedRefused:
      return "correct: feed reading refused: a value is beyond the correction limit (the correction keeps the last good "
             "reading; the summary names the last one refused)";
    default: return OpenModeApp::note_text(c);
  }
}

std::string CorrectApp::status() const {
  std::string out = OpenModeApp::status() + " correction[turns]";
  for (std::size_t j = 0; j < 6 && j < protocol::kAxesPerArm; ++j) out += fmt::format(" {:.4f}", applied(j));
  return out;
}

std::string CorrectApp::summary() const {
  std::string out = App::summary() + fmt::format("correct: {:.3f} s corrected, phase {}\n", elapsed_s(), to_string(phase()));
  if (options_.feed) {
    out += fmt::format("correct: feed on port {}: {} datagrams accepted, {} rejected, {} from other senders ignored, "
                       "{} readings refused beyond the limits, {} stale cycles, {} cycles slewed\n", options_.feed->port(),
                       options_.feed->accepted(), options_.feed->rejected(), options_.feed->foreign(), refused_samples(),
                       stale_cycles(), slewed_cycles());
    if (const auto e = options_.feed->last_error(); !e.empty()) out += "correct: last rejected datagram " + e + "\n";
    if (refused_samples() > 0) {
      const int j = refused_axis_.load(std::memory_order_relaxed);
      out += fmt::format("correct: last refused reading: axis {} = {:g} deg, beyond the correction limit {:g} deg\n", j + 1,
                         refused_value_.load(std::memory_order_relaxed) * kRadToDeg,
                         options_.limits.max_abs(static_cast<std::size_t>(j)) * kRadToDeg);
    }
  }
  return out;
}

}  // namespace axon::c4g::apps
