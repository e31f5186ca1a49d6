#include "axon/c4g/protocol/mode.hpp"

#include <algorithm>
#include <charconv>

namespace axon::c4g::protocol {
namespace {

constexpr FieldMask kNone = 0;
using K = ModeKind;
using O = Origin;

// In code order. pc_fields: what the PC's reply must carry for the mode to do anything (all fields
// are always on the wire; the others are sent as zero).
constexpr std::array<ModeInfo, 31> kModes{{
    {Mode::mode0, "mode0", "0", "controller generates the trajectory and closes the loops; the PC only answers", K::standard,
     O::controller, true, kNone},
    {Mode::mode1, "mode1", "1",
     "PC generates the trajectory and closes position and velocity loops: target position and velocity, "
     "current (and optionally velocity) contribution; PC checks following error and saturates currents",
     K::standard, O::controller, true, kFieldD1 | kFieldD2 | kFieldD4 | kFieldD5},
    {Mode::mode2, "mode2", "2",
     "controller generates the trajectory, PC closes the loops: velocity and current contributions; PC checks "
     "following error and saturates currents",
     K::standard, O::controller, true, kFieldD4 | kFieldD5},
    {Mode::mode3, "mode3", "3", "controller generates a velocity trajectory, PC closes the velocity loop (current)",
     K::standard, O::controller, false, kFieldD5},
    {Mode::mode4, "mode4", "4",
     "PC generates an absolute position trajectory (target position and velocity, calibration constants "
     "included); controller closes the loops",
     K::standard, O::controller, true, kFieldD1 | kFieldD2},
    {Mode::mode5, "mode5", "5",
     "PC generates a relative position trajectory (position increment and velocity) that the controller "
     "integrates; controller closes the loops",
     K::standard, O::controller, true, kFieldD1 | kFieldD2},
    {Mode::mode6, "mode6", "6", "PC generates a velocity trajectory; controller closes the velocity loop", K::standard,
     O::controller, false, kFieldD2},
    {Mode::mode7, "mode7", "7",
     "controller generates the trajectory, PC adds a position correction (increment in target position)",
     K::standard, O::controller, true, kFieldD1},
    {Mode::mode8, "mode8", "8", "controller generates the trajectory, PC adds a velocity contribution", K::standard,
     O::controller, false, kFieldD4},
    {Mode::mode9, "mode9", "9",
     "controller generates the trajectory, PC adds a current contribution (the controller's dynamic model "
     "current and inertia arrive in EXT1/EXT2)",
     K::standard, O::controller, true, kFieldD5},
    {Mode::mode0_prime, "mode0_prime", "0'",
     "echo test reserved to the maker: the PC returns the target position and velocity unchanged", K::standard,
     O::controller, true, kFieldD1 | kFieldD2},
    {Mode::mode1_standby, "mode1_standby", "1'",
     "leaving mode 1: the PC keeps holding the robot (targets and current) while control ramps back", K::standby,
     O::controller, true, kFieldD1 | kFieldD2 | kFieldD4 | kFieldD5},
    {Mode::mode2_standby, "mode2_standby", "2'",
     "leaving mode 2: the PC keeps closing the loops while control ramps back", K::standby, O::controller, true,
     kFieldD4 | kFieldD5},
    {Mode::mode4_standby, "mode4_standby", "4'", "leaving mode 4: the PC holds its last target", K::standby,
     O::controller, true, kFieldD1 | kFieldD2},
    {Mode::mode5_standby, "mode5_standby", "5'", "leaving mode 5: the PC holds its last target", K::standby,
     O::controller, true, kFieldD1 | kFieldD2},
    {Mode::mode7_standby, "mode7_standby", "7'",
     "leaving mode 7 while the controller still moves: the PC sends a zero correction", K::standby, O::controller,
     true, kFieldD1},
    {Mode::sensor, "sensor", "1xx", "the PC passes an external sensor's measure", K::sensor, O::controller, false,
     kFieldD3},
    {Mode::sensor_accelerometer, "sensor_accelerometer", "101", "the PC passes accelerometer measures", K::sensor,
     O::controller, false, kFieldD3},
    {Mode::sensor_camera, "sensor_camera", "102", "the PC passes camera measures (visual servoing)", K::sensor,
     O::controller, false, kFieldD3},
    {Mode::sensor_force, "sensor_force", "103", "the PC passes force/torque sensor measures", K::sensor, O::controller,
     false, kFieldD3},
    {Mode::mode7_standby_exit, "mode7_standby_exit", "170",
     "last step out of mode 7: the PC sends zero references", K::standby, O::controller, true, kNone},
    {Mode::cartesian_target, "cartesian_target", "201",
     "the PC sends a Cartesian target (layout not specified by the manual)", K::cartesian, O::controller, false,
     kFieldD1},
    {Mode::cartesian_delta, "cartesian_delta", "202",
     "the PC sends a Cartesian correction (layout not specified by the manual)", K::cartesian, O::controller, false,
     kFieldD1},
    {Mode::freezing_active, "freezing_active", "500",
     "sent by the PC (from mode 0): the controller stops checking the PC's replies until INFPAR carries "
     "exit-from-open",
     K::special, O::pc, true, kNone},
    {Mode::driving_on, "driving_on", "501",
     "forced by the controller while the drives are switched on; mode requests are ignored", K::special,
     O::controller, true, kNone},
    {Mode::freezing_passive_in, "freezing_passive_in", "502",
     "the controller stops sending packets for a while (from mode 0)", K::special, O::controller, true, kNone},
    {Mode::freezing_passive_out, "freezing_passive_out", "503", "the controller resumes sending packets", K::special,
     O::controller, true, kNone},
    {Mode::exit_open, "exit_open", "504",
     "the controller ends the real-time exchange for good (from mode 0); the PC may stop serving", K::special,
     O::controller, true, kNone},
    {Mode::drive_off, "drive_off", "505", "sent by the PC: switch the drives off, then mode 0", K::special, O::pc,
     true, kNone},
    {Mode::server_restart, "server_restart", "506",
     "the controller restarts its client side; an initialization packet follows", K::special, O::controller, true,
     kNone},
    {Mode::following_error, "following_error", "508",
     "sent by the PC: a following error exceeded its threshold; the controller reports it and drives off",
     K::special, O::pc, true, kNone},
}};

bool iequal(std::string_view a, std::string_view b) noexcept {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           auto low = [](char c) { return c >= 'A' && c <= 'Z' ? static_cast<char>(c - 'A' + 'a') : c; };
           return low(x) == low(y);
         });
}

}  // namespace

const ModeInfo* find_mode(std::int32_t c) noexcept {
  for (const ModeInfo& m : kModes)
    if (code(m.mode) == c) return &m;
  if (c > 100 && c < 200) return find_mode(code(Mode::sensor));
  return nullptr;
}

std::string_view mode_name(std::int32_t c) noexcept {
  const ModeInfo* m = find_mode(c);
  return m != nullptr ? m->name : std::string_view("unknown");
}

std::span<const ModeInfo> all_modes() noexcept { return kModes; }

std::optional<std::int32_t> parse_mode(std::string_view text) noexcept {
  for (const ModeInfo& m : kModes)
    if (iequal(text, m.name) || iequal(text, m.label)) return code(m.mode);
  std::int32_t v = 0;
  const auto [p, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec == std::errc{} && p == text.data() + text.size() && is_known_mode(v)) return v;
  return std::nullopt;
}

Fault check_modes(const Packet& pkt) noexcept {
  int i = 0;
  for (const Axis& a : pkt.open_axes()) {
    if (!is_known_mode(a.mode)) {
      Fault f;
      f.code = ProtocolErrc::unknown_mode;
      f.axis = i;
      f.field = 0;
      f.got = a.mode;
      return f;
    }
    ++i;
  }
  return {};
}

FieldMask nonzero_fields(const Axis& a) noexcept {
  const float v[8] = {a.d1, a.d2, a.d3, a.d4, a.d5, a.ext1, a.ext2, a.ext3};
  FieldMask m = 0;
  for (int k = 0; k < 8; ++k)
    if (!(v[k] == 0.0f)) m = static_cast<FieldMask>(m | (1u << (k + 1)));
  return m;
}

Fault check_reply_fields(const Packet& reply) noexcept {
  int i = 0;
  for (const Axis& a : reply.open_axes()) {
    const ModeInfo* info = find_mode(a.mode);
    const FieldMask extra = info != nullptr ? static_cast<FieldMask>(nonzero_fields(a) & ~info->pc_fields) : FieldMask{0};
    if (extra != 0) {
      Fault f;
      f.code = ProtocolErrc::field_not_null;
      f.axis = i;
      for (int k = 1; k <= 8 && f.field < 0; ++k)
        if (extra & (1u << k)) f.field = k;
      f.got = a.mode;
      return f;
    }
    ++i;
  }
  return {};
}

ModeChange check_mode_change(std::int32_t current, std::int32_t requested, bool exit_from_open_sent) noexcept {
  if (requested == current) return ModeChange::unchanged;
  if (!is_known_mode(requested)) return ModeChange::unknown_mode;
  if (requested == code(Mode::drive_off) || requested == code(Mode::following_error)) return ModeChange::allowed;
  if (current == code(Mode::driving_on)) return ModeChange::driving_on;
  const ModeInfo* r = find_mode(requested);
  if (requested == code(Mode::mode2_standby) && current == code(Mode::mode2)) return ModeChange::allowed;
  if (r->kind == ModeKind::standby || (r->kind == ModeKind::special && r->origin == Origin::controller &&
                                       requested != code(Mode::server_restart)))
    return ModeChange::controller_only;
  if (current == code(Mode::mode0)) return ModeChange::allowed;
  if (r->kind == ModeKind::special) return ModeChange::not_from_mode0;  // specials need mode 0 first
  return exit_from_open_sent ? ModeChange::allowed : ModeChange::not_from_mode0;
}

std::string_view to_string(ModeChange c) noexcept {
  switch (c) {
    case ModeChange::allowed: return "allowed";
    case ModeChange::unchanged: return "unchanged";
    case ModeChange::unknown_mode: return "unknown mode";
    case ModeChange::driving_on: return "refused while the drives are switching on";
    case ModeChange::not_from_mode0: return "refused: change modes from mode 0 or after exit-from-open";
    case ModeChange::controller_only: return "refused: only the controller issues this code";
  }
  return "?";
}

std::optional<std::int32_t> standby_of(std::int32_t m) noexcept {
  switch (m) {
    case 1: return 11;
    case 2: return 12;
    case 4: return 14;
    case 5: return 15;
    case 7: return 17;
    default: return std::nullopt;
  }
}

std::optional<std::int32_t> base_of_standby(std::int32_t s) noexcept {
  switch (s) {
    case 11: return 1;
    case 12: return 2;
    case 14: return 4;
    case 15: return 5;
    case 17:
    case 170: return 7;
    default: return std::nullopt;
  }
}

ModeSequence exit_sequence(std::int32_t m, bool controller_motion_finished) noexcept {
  ModeSequence s;
  auto push = [&](std::int32_t c) { s.codes[s.count++] = c; };
  switch (m) {
    case 1: case 2: case 4: case 5:
      push(*standby_of(m));
      push(0);
      break;
    case 7:
      if (!controller_motion_finished) push(17);
      push(170);
      push(0);
      break;
    case 3: case 6: case 8: case 9:
      push(0);
      break;
    default:
      if (find_mode(m) != nullptr && (find_mode(m)->kind == ModeKind::sensor || find_mode(m)->kind == ModeKind::cartesian))
        push(0);
      break;
  }
  return s;
}

ModePhases phases(std::int32_t m) noexcept {
  ModePhases p;
  switch (m) {
    case 0:
      p.end_by = EndTrigger::controller_sets_mode;
      p.start = "the controller program sets mode 0, or another mode ends";
      p.end = "the controller program sets another mode";
      break;
    case 10:
      p.end_by = EndTrigger::controller_sets_mode;
      p.start = "the controller program sets mode 0'";
      p.end = "the controller program sets another mode";
      break;
    case 1:
      p.has_cruise = true;
      p.end_by = EndTrigger::pc_exit_from_open;
      p.start = "the controller program sets mode 1; control ramps from the drive to the PC while the PC holds the robot";
      p.cruise = "the ramp is complete and the PC starts its trajectory";
      p.end = "the PC sends exit-from-open: mode 1' while control ramps back, then mode 0";
      break;
    case 2:
      p.has_cruise = true;
      p.end_by = EndTrigger::pc_exit_from_open;
      p.start = "the controller program sets mode 2; control ramps from the drive to the PC during a program delay";
      p.cruise = "the ramp and the delay are over and the controller program moves the robot";
      p.end = "mode 2' is set; control ramps back to the drive, then mode 0";
      break;
    case 4: case 5: case 7: case 8: case 9:
      p.end_by = EndTrigger::pc_exit_from_open;
      p.start = "the controller program sets the mode";
      p.end = m == 7 ? "the PC sends exit-from-open: 7' while the controller still moves, then 7'' (170), then mode 0"
                     : "the PC sends exit-from-open, then mode 0";
      break;
    default:
      break;
  }
  return p;
}

std::optional<MotionState> next_state(MotionState s, MotionEvent e) noexcept {
  using S = MotionState;
  using E = MotionEvent;
  switch (s) {
    case S::stop:
      if (e == E::move) return S::closed;
      if (e == E::go_open_a) return S::open_a;
      if (e == E::go_open_b) return S::open_b;
      return std::nullopt;
    case S::closed:
      if (e == E::motion_end) return S::stop;
      return std::nullopt;  // entering open while moving is not allowed
    case S::open_a:
      if (e == E::exit_from_open) return S::stop;
      return std::nullopt;
    case S::open_b:
      if (e == E::exit_from_open) return S::closed;  // the controller's motion goes on
      if (e == E::motion_end) return S::open_a;      // the PC's part goes on
      return std::nullopt;
  }
  return std::nullopt;
}

std::string_view to_string(MotionState s) noexcept {
  switch (s) {
    case MotionState::stop: return "stop";
    case MotionState::closed: return "closed";
    case MotionState::open_a: return "open_a";
    case MotionState::open_b: return "open_b";
  }
  return "?";
}

std::string_view to_string(MotionEvent e) noexcept {
  switch (e) {
    case MotionEvent::move: return "move";
    case MotionEvent::motion_end: return "motion_end";
    case MotionEvent::go_open_a: return "go_open_a";
    case MotionEvent::go_open_b: return "go_open_b";
    case MotionEvent::exit_from_open: return "exit_from_open";
  }
  return "?";
}

}  // namespace axon::c4g::protocol
