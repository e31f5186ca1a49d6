// The simulated robot controller (the SMP+ side of the open interface): the UDP client's logic,
// without any I/O or clock of its own.
//
// One tick per controller period. The transport calls, every period:
//   1. begin_cycle()        -> the datagram to send now (empty: nothing to send this tick);
//   2. on_datagram(bytes)   for each datagram that arrives before the reply deadline
//                           (reply_received() tells when the awaited answer is in);
//   3. end_cycle()          at the deadline or once the reply is in: judges the reply, applies the
//                           PC's data per mode, runs the mode state machine and the robot program,
//                           and integrates the axes over one period.
//
// Communication: sync packets (cyclic layout, mode 0) until `sync_packets` were answered, then the
// initialization packet, then the cyclic packets. Each cyclic packet must be answered, before the
// deadline, with its protocol number (or NUM + 1 with ReplyNumbering::next); a missing, late,
// wrongly numbered, wrongly sized or malformed reply is a miss, counted by kind; `max_misses` (10)
// consecutive misses raise ERR_C4GOPEN_UDP, switch the drives off and stop the exchange for good.
//
// Modes (per axis, from the program or the PC): 0, 0', 1, 2, 4, 5, 7, 8, 9, 1xx applied as in
// docs/c4g-simulator.md; standby codes on the PC's exit-from-open (protocol::exit_sequence); special
// codes 500 (active freezing, from the PC), 501 (during drive on), 502/503 (passive freezing, program),
// 504 (end of exchange, program), 505 (drive off, PC), 506 (restart: new initialization packet, from
// the program or the PC), 508 (following error, PC).
#pragma once

#include "axon/c4g/protocol/axis_map.hpp"
#include "axon/c4g/protocol/init_packet.hpp"
#include "axon/c4g/protocol/mode.hpp"
#include "axon/c4g/protocol/packet.hpp"
#include "axon/c4g/protocol/transform.hpp"
#include "axon/c4g/sim/axis_model.hpp"
#include "axon/c4g/sim/events.hpp"
#include "axon/c4g/sim/robots.hpp"
#include "axon/c4g/sim/scenario.hpp"
#include "axon/c4g/sim/soft_switch.hpp"
#include "axon/core/error.hpp"

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace axon::c4g::sim {

struct ControllerOptions {
  protocol::ReplyNumbering numbering = protocol::ReplyNumbering::same;
  int sync_packets = 3;          // answered sync packets before the initialization packet
  double sync_timeout_s = 300;   // no answer during the sync phase for this long: communication error
  int max_misses = 10;           // consecutive misses that raise ERR_C4GOPEN_UDP (the manual: 10)
  int period_ms = 0;             // 0: the robot's period (initialization packet); else 1 or 2
  std::int32_t first_number = 1; // protocol number of the first packet
};

enum class Phase { sync, init, cycle, passive_freeze, ended, failed };
std::string_view to_string(Phase p) noexcept;

struct ControllerStats {
  std::uint64_t ticks = 0;             // controller periods simulated
  std::uint64_t packets_sent = 0;      // datagrams of every kind
  std::uint64_t sync_sent = 0;
  std::uint64_t init_sent = 0;
  std::uint64_t cyclic_sent = 0;
  std::uint64_t replies_ok = 0;        // answered in time with the right number (sync and cyclic)
  std::uint64_t misses = 0;            // cyclic packets without a good reply (while checked)
  std::uint64_t max_consecutive_misses = 0;
  std::uint64_t late_replies = 0;      // replies to an earlier packet
  std::uint64_t wrong_number = 0;      // replies carrying a number never sent recently
  std::uint64_t wrong_size = 0;        // datagrams of another size than a cyclic packet of n axes
  std::uint64_t malformed = 0;         // right size but not decodable (NaN, number out of range)
  std::uint64_t duplicate_replies = 0; // a second good reply to the same packet
  std::uint64_t init_answers = 0;      // answers to the initialization packet (optional)
  std::uint64_t frozen_cycles = 0;     // cycles not checked (active or passive freezing)
  std::uint64_t refused_requests = 0;  // mode codes from the PC the rules do not allow
  std::uint64_t saturated_cycles = 0;  // axis-cycles whose reference current hit its limit
};

class Controller {
 public:
  static Result<Controller> create(RobotConfig robot, Scenario scenario, ControllerOptions options = {});

  // ---- the tick protocol ----
  std::span<const std::byte> begin_cycle();
  void on_datagram(std::span<const std::byte> datagram);
  [[nodiscard]] bool reply_received() const noexcept { return reply_ok_; }
  [[nodiscard]] bool awaiting_reply() const noexcept { return awaiting_; }
  void end_cycle();
  // The transport could not send (ERR_C4GOPEN_TX_UDP); the tick counts as a miss.
  void on_send_failed(std::string_view why);

  // ---- state ----
  [[nodiscard]] Phase phase() const noexcept { return phase_; }
  [[nodiscard]] double period_s() const noexcept { return period_; }
  [[nodiscard]] double time_s() const noexcept { return static_cast<double>(stats_.ticks) * period_; }
  [[nodiscard]] const ControllerStats& stats() const noexcept { return stats_; }
  [[nodiscard]] bool communication_error() const noexcept { return comm_error_; }
  [[nodiscard]] bool scenario_done() const noexcept { return scenario_done_; }
  [[nodiscard]] bool scenario_running_forever() const noexcept { return running_forever_; }
  [[nodiscard]] bool scenario_failed() const noexcept { return !scenario_error_.empty(); }
  [[nodiscard]] const std::string& scenario_error() const noexcept { return scenario_error_; }
  // True when the run should stop: the exchange failed, ended, or the program finished (not `run`).
  [[nodiscard]] bool finished() const noexcept;
  std::vector<Event> take_events();

  [[nodiscard]] const RobotConfig& robot() const noexcept { return robot_; }
  [[nodiscard]] const protocol::InitPacket& init() const noexcept { return robot_.init; }
  [[nodiscard]] const protocol::AxisMap& axis_map() const noexcept { return map_; }
  [[nodiscard]] std::size_t axis_count() const noexcept { return map_.count(); }
  [[nodiscard]] std::int32_t axis_mode(std::size_t open) const noexcept { return axes_[open].mode; }
  [[nodiscard]] double axis_position(std::size_t open) const noexcept { return axes_[open].model.position(); }
  [[nodiscard]] double axis_velocity(std::size_t open) const noexcept { return axes_[open].model.velocity(); }
  [[nodiscard]] double axis_current(std::size_t open) const noexcept { return axes_[open].model.current(); }
  [[nodiscard]] double axis_reference(std::size_t open) const noexcept { return axes_[open].ref_pos; }
  [[nodiscard]] const AxisModel& axis_model(std::size_t open) const noexcept { return axes_[open].model; }
  // Soft control switching of an axis as of the last period (interval none when no switch is under way).
  [[nodiscard]] const protocol::SwitchSample& axis_switch(std::size_t open) const noexcept { return axes_[open].scs.last(); }
  [[nodiscard]] float axis_measure(std::size_t open) const noexcept { return axes_[open].measure; }
  [[nodiscard]] bool drives_on(std::size_t arm) const noexcept;
  // Joint positions of an arm at the link [deg], from the motor positions.
  [[nodiscard]] std::vector<double> joint_degrees(std::size_t arm) const;
  // The same into `out` without allocating (at most out.size() joints; returns how many): from the
  // motor positions, or (target) from the targets the packets report (D1).
  std::size_t link_degrees(std::size_t arm, bool target, std::span<double> out) const noexcept;
  // The mode code the PC's last good reply asked for on an open axis.
  [[nodiscard]] std::int32_t axis_pc_request(std::size_t open) const noexcept { return axes_[open].last_request; }
  // The open mode the robot program's GO OPEN asked for on an arm; 0 while no GO OPEN is in force.
  [[nodiscard]] std::int32_t arm_program_mode(std::size_t arm) const noexcept {
    return arm >= 1 && arm <= protocol::kMaxArms && arms_[arm].open ? arms_[arm].open_mode : 0;
  }
  // The program's step under way (0-based; the step count once it ended) and the program.
  [[nodiscard]] std::size_t step_index() const noexcept { return step_index_; }
  [[nodiscard]] const Scenario& scenario() const noexcept { return scenario_; }
  [[nodiscard]] int consecutive_misses() const noexcept { return consecutive_misses_; }

 private:
  struct ExitSeq {
    protocol::ModeSequence seq;
    std::size_t index = 0;
    int remaining = 0;
    bool active = false;
  };
  struct AxisSim {
    std::uint8_t arm = 0;   // 1..4
    std::uint8_t axis = 0;  // logical 1..10
    std::int32_t mode = 0;
    std::int32_t mode_before_special = 0;
    AxisModel model;
    double traj_pos = 0, traj_vel = 0, traj_acc = 0;  // the controller's trajectory [turns, /s, /s^2]
    double offset = 0;        // modes 5, 7: accumulated PC increments (absorbed when the mode ends)
    double hold_pos = 0;      // modes 1, 2: where the DSA holds while control switches
    double ref_pos = 0, ref_vel = 0, prev_ref_pos = 0;  // reported target; previous DSA reference
    double dsa_ref = 0;       // the position reference the DSA tracked last period
    SoftSwitch scs;           // soft control switching entering/leaving modes 1 and 2
    protocol::Axis pc{};      // the PC's data from the last good reply
    std::int32_t last_request = 0;
    std::int32_t sent_mode = 0;   // the code in the last packet sent
    float measure = 0;        // 1xx: the last measure from the PC
    ExitSeq exit;
  };
  struct Move {
    bool active = false;
    std::array<double, protocol::kAxesPerArm> start{}, goal{};  // motor turns, by logical axis
    double duration = 0, elapsed = 0;
  };
  struct ArmSim {
    bool present = false;
    bool powered = false;     // drives on (also during the procedure's end)
    int drive_on_left = 0;    // ticks of the drive-on procedure left (mode 501 meanwhile)
    int drive_off_left = 0;   // ticks showing the drive-off request code
    std::int32_t drive_off_code = 0;
    bool open = false;        // a GO OPEN is in progress (until its exit sequence ends)
    OpenType type = OpenType::a;
    std::int32_t open_mode = 0;
    bool exit_while_moving = false;  // type B: the PC's exit-from-open came before the controller's move ended
    std::uint8_t cmd = 0;
    Move move;
    std::optional<protocol::ArmTransform> transform;
  };

  Controller() = default;
  void emit(EventLevel level, std::string_view name, std::string text);
  void encode_cyclic(std::int32_t force_mode);
  void judge_datagram(std::span<const std::byte> d);
  void cyclic_tick();
  void apply_reply();
  void handle_request(std::size_t i, std::int32_t req);
  void handle_mode_request(std::size_t i, std::int32_t req, const std::function<void(std::string_view)>& refuse);
  void advance_modes();
  void set_mode(std::size_t i, std::int32_t mode, std::string_view why);
  void set_arm_mode(std::size_t arm, std::int32_t mode, std::string_view why);
  void start_exit(std::size_t arm);
  int standby_ticks(std::int32_t code) const;
  bool all_axes_in_mode0() const;
  void finish_open_mode(std::size_t i);
  void drive_off(std::size_t arm, std::int32_t shown_code);
  void start_drive_on(std::size_t arm);
  void communication_failure(std::string_view why);
  void advance_moves();
  void step_physics();
  void check_following_error();
  void check_soft_switch();
  void check_offset_limit();
  // The state selector moved: every arm not in mode 0 is forced there, without its exit.
  void force_mode0(std::size_t arm);
  void run_scenario();
  bool start_step(const Step& s);
  bool step_complete(const Step& s);
  void fail_scenario(const Step& s, std::string_view why);
  std::vector<std::size_t> step_arms(const Step& s) const;
  bool arm_idle(std::size_t arm) const;
  bool arm_moving(std::size_t arm) const;  // an axis faster than the soft-switching still velocity
  double ticks_to_s(std::uint64_t t) const noexcept { return static_cast<double>(t) * period_; }

  RobotConfig robot_;
  Scenario scenario_;
  ControllerOptions options_;
  protocol::AxisMap map_;
  double period_ = 0.002;
  Phase phase_ = Phase::sync;
  std::array<AxisSim, protocol::kMaxAxes> axes_{};
  std::array<ArmSim, protocol::kMaxArms + 1> arms_{};  // index 1..4

  std::array<std::byte, protocol::kInitPacketSize> tx_{};
  std::size_t tx_size_ = 0;
  std::int32_t num_ = 0;
  std::int32_t expected_ = -1;
  std::array<std::int32_t, 8> recent_{};  // numbers answered in earlier ticks, for late replies
  std::size_t recent_next_ = 0;
  bool awaiting_ = false;
  bool reply_ok_ = false;
  bool sent_cyclic_ = false;
  protocol::Packet reply_{};
  protocol::Packet scratch_{};

  int sync_answered_ = 0;
  std::uint64_t sync_last_answer_tick_ = 0;
  int consecutive_misses_ = 0;
  bool comm_error_ = false;
  bool frozen_active_ = false;
  bool scenario_started_ = false;
  bool selector_prog_ = false;    // the state selector in PROG (open modes need AUTO)
  int override_percent_ = 100;    // the general override: scales mode 5's increments  // the robot program runs once the cyclic exchange started
  std::array<bool, protocol::kMaxArms + 1> exit_requested_{};
  // Program-issued special codes waiting for their packet: 502 -> freeze, 503 -> back to 0,
  // 504 -> end, 506 -> initialization packet.
  std::int32_t pending_special_ = 0;
  std::int32_t special_in_packet_ = 0;  // the special code the last cyclic packet carried (0: none)
  std::uint64_t passive_left_ = 0;
  bool passive_out_pending_ = false;

  std::size_t step_index_ = 0;
  bool step_started_ = false;
  std::uint64_t step_start_tick_ = 0;
  bool scenario_done_ = false;
  bool running_forever_ = false;
  std::string scenario_error_;
  ControllerStats stats_;
  std::vector<Event> events_;
};

}  // namespace axon::c4g::sim
