// axon::fps::Client: the fiber positioners from a plain program, without Asio. Every call blocks
// until it is done and returns plain values; the work runs on an event loop the client owns, on a
// thread of its own (core::LoopThread), over the coroutine API (fps::host::Array,
// FocalPlaneArray), which stays there for programs that want it.
//
//   axon::fps::Client fps;
//   fps.open(axon::fps::resolve_layout("site.yaml").value());   // or open({"cannet://10.0.0.1/1", ...})
//   for (const auto& r : fps.discover()) std::printf("%u %s\n", r.id, r.state.c_str());
//   fps.plan_and_move({{12, {90, 150}}, {13, {200, 170}}});
//
// Errors: a call that cannot do its job throws axon::Exception, whose error() carries the code
// (fps::host::HostErrc: locked, unknown_positioner, ...; fps::plan::PlanErrc for plans and targets;
// can and net codes for the connection; CoreErrc::timeout) and a message. What happened to each
// robot of a move that did run is in the returned outcome, not thrown.
//
// Timeouts: every reply has ClientConfig::reply_timeout_s; a whole call has call_timeout_s (a move
// takes its trajectory's duration plus margins, so that bound is generous). A call that overruns it
// stops every robot (as emergency_stop() does: TRAJECTORY_ABORT on every bus, the array locked),
// waits for the call to end, then throws CoreErrc::timeout; unlock() lets the robots move again.
//
// Safety: the array locks on a collision report from any robot and aborts every robot on every
// bus (Array); a locked client refuses moves (HostErrc::locked) until unlock(). The destructor (and
// close()) stop robots this client set moving, close the connections and never throw.
//
// Threading: one thread at a time may call a client (calls are not queued against each other);
// interrupt(), locked(), lock_reason() are the exceptions: any thread may call them (while open).
#pragma once

#include "axon/fps/host/troubleshoot_types.hpp"
#include "axon/fps/layout/focal_plane.hpp"
#include "axon/fps/layout/layout_check.hpp"

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace boost::asio {
class io_context;
}

namespace axon::fps {

namespace host {
class FocalPlaneArray;
}

struct Angles {
  double alpha = 0;  // degrees
  double beta = 0;
};

struct ClientConfig {
  double reply_timeout_s = 1.0;    // each command's reply
  double call_timeout_s = 600.0;   // each blocking call, start to end
  double poll_interval_s = 0.25;   // status polling while robots move
  double discover_window_s = 0.5;  // GET_ID answers collected by discovery
  double position_tolerance_deg = 0.1;  // a move ends this close to its target, per arm
  // Firmware versions (docs/fps-host.md): the field's command history (the precise-move switches
  // from 04.01.17 on; commands a robot's version lacks fail with HostErrc::firmware_lacks unsent)
  // instead of the document's, and GET_FIRMWARE_VERSION's bytes in the document's order.
  bool field_firmware_history = false;
  bool document_version_byte_order = false;
  // The PLC (positioner power and the sync line) at HOST[:PORT] (port 502 by default), connected by
  // open(plane); upgrade_firmware() and a start by the sync line need it. "": none.
  std::string plc_address{};
  // A start by the sync line holds the line high this long (FIELD-NOTES: about 0.5 s in service;
  // the robots need a few milliseconds).
  double sync_hold_s = 0.5;
};

// One robot's row of status(): plain values.
struct RobotStatus {
  std::uint16_t id = 0;
  std::string bus;                  // bus name (cannet://HOST:PORT/N)
  std::string state;                // ready, moving, collision, calibrating, no-datum, bootloader, no-reply
  bool ready = false;
  std::string firmware;             // "04.01.13", empty when unknown
  std::vector<std::string> flags;   // status flags set
  std::optional<Angles> position;   // application robots that answered
  std::string error;                // why it did not answer
};

// One robot of a move.
struct RobotMove {
  std::uint16_t id = 0;
  bool ok = false;                 // reached its target
  std::string state;               // completed, collided, timeout, not_ready, ...
  std::optional<Angles> target;
  std::optional<Angles> reached;
  std::string detail;              // why not, when not ok
};

struct MoveOutcome {
  bool completed = false;          // every robot reached its target
  std::string summary;             // one line per robot that did not
  std::vector<RobotMove> robots;   // in id order
  [[nodiscard]] const RobotMove* find(std::uint16_t id) const noexcept;
};

// A firmware trajectory as points in degrees and seconds after the start (the robot adds where it
// stands as the first point); an arm without points stays.
struct ArmPath {
  std::vector<std::pair<double, double>> alpha;  // (degrees, seconds)
  std::vector<std::pair<double, double>> beta;
};

struct PlanSettings {
  double speed_deg_s = 12.0;     // both arms (2000 rpm at the motor, 1000:1)
  double buffer_mm = 2.0;        // collision buffer of every robot
  std::uint64_t seed = 1;        // the planner's nudges
  bool park_bad_targets = true;  // false: a bad target fails the call instead of parking that robot
  bool allow_partial = false;    // move the others when some robots cannot reach their targets
  // Targets outside their robots' safe zones (spec section 11: the arms' length and angle errors;
  // docs/fps-plan.md): true refuses the call (PlanErrc::outside_safe_zone naming the robots and by
  // how much) before anything moves; false only reports them in PlanOutcome.
  bool refuse_outside_safe_zone = false;
  // Start the planned trajectories by a pulse of the PLC's sync line (open(plane) with
  // ClientConfig::plc_address) instead of the START_TRAJECTORY broadcast.
  bool start_by_sync_line = false;
};

struct PlanOutcome {
  bool verified = false;           // the independent checker found no contact
  std::size_t robots = 0;
  std::size_t not_reached = 0;     // parked or held
  double move_s = 0;               // duration of the move
  double plan_s = 0;               // planning wall time
  double min_clearance_mm = 0;
  std::map<std::uint16_t, Angles> ends;  // where the plan leaves each robot
  std::string notes;               // targets parked, robots held (one line each)
  std::vector<std::uint16_t> outside_safe_zone;  // robots whose targets leave their safe zones
  std::string safe_zone;           // why, one line each ("robot 12: target 0.180 mm beyond ...")
};

struct PlanAndMoveOutcome {
  PlanOutcome plan;
  bool moved = false;              // false: every robot already stood at its end
  MoveOutcome move;
};

struct StopOutcome {
  std::string reason;
  std::size_t robots_reached = 0;  // robots on the buses where the abort went out
  std::size_t buses_sent = 0;
  std::size_t buses = 0;
  std::string text;                // StopReport::to_text()
};

// The steps of calibrate(), run in the order of the document's calibration chapter.
struct CalibrationSteps {
  bool motors = true;
  bool datums = true;
  bool cogging = false;  // long (up to 40 minutes) and not essential
  bool save = true;      // write the results to the robot's flash
};

struct CalibrationOutcome {
  std::optional<Angles> motor_error;  // degrees (whole), after the motor calibration
  std::optional<Angles> datum_error;  // degrees (whole: the spread of the hard-stop hits)
  bool saved = false;
  std::vector<std::string> flags;     // the robot's status flags at the end
};

struct UnlockOutcome {
  std::vector<std::uint16_t> acknowledged;
  std::vector<std::uint16_t> silent;
};

// One robot moved away from what it touched (or why it was not).
struct BackOffMove {
  std::uint16_t id = 0;
  bool moved = false;
  char arm = 0;         // 'a' or 'b': the arm that turned
  double step_deg = 0;  // signed
  Angles from;
  Angles to;
  double clearance_before_mm = 0;  // to the nearest body, at the full collision buffer
  double clearance_after_mm = 0;   // as planned
  std::string problem;             // why it did not move ("" when it did)
};

struct BackOffOutcome {
  std::vector<std::string> contacts_before;  // "robot 1 / robot 2 (-0.083 mm)"
  std::vector<BackOffMove> moves;
  std::vector<std::string> contacts_after;
  bool ok = false;      // every robot moved and no contact is left
  std::string summary;  // one line per move and contact
};

// What upgrade_firmware() does (host/plane_upgrade.hpp).
struct UpgradeSettings {
  std::string expected_version;  // "XX.YY.ZZ" every robot must run afterwards; "": reported, not checked
  std::vector<int> sextants;     // empty: every sextant with robots, in order
  unsigned retries = 1;          // extra attempts per robot that failed
  double power_off_s = 1.0;      // positioner power off this long before each power-up
};

// Where one sextant's upgrade stands: the progress callback's argument, about once a second while
// its robots receive the image and once at its end.
struct SextantUpgrade {
  int sextant = 0;
  std::size_t robots = 0;  // of the sextant
  std::size_t done = 0;    // upgraded and verified so far
  std::size_t failed = 0;
  std::uint64_t bytes = 0;  // image bytes the robots acknowledged
  double seconds = 0;       // since the sextant started
  bool finished = false;
  std::string text;         // "sextant 2: 83/84 robots, 1 failed, 4.13 MB in 12.1 s (341.2 kB/s)"
};

struct RobotUpgrade {
  std::uint16_t id = 0;
  int sextant = 0;
  std::string outcome;     // ok, failed, not_attempted
  unsigned attempts = 0;
  std::string reason;      // why not ok; notes when ok
  bool half_written = false;  // its last transfer stopped part-way (it runs its previous firmware)
  std::string before;      // application version before ("" unknown)
  std::string after;       // what it runs at the end ("" no answer)
};

struct FirmwareOutcome {
  bool ok = false;  // every robot runs the new image
  std::vector<RobotUpgrade> robots;
  std::string summary;  // one line per sextant, then one per robot that is not plainly ok
};

// What apply_cold_policy() decided from the PLC's temperatures and sent (docs/fps-plc.md).
struct ColdOutcome {
  std::uint32_t motor_rpm = 0;        // the speed every robot was given
  double alpha_holding_pct = 0;       // holding currents
  double beta_holding_pct = 0;
  std::optional<double> coldest_c;    // the coldest valid reading (nullopt: none)
  std::string coldest_sensor;
  std::vector<std::uint16_t> applied;            // robots that took both settings
  std::map<std::uint16_t, std::string> failed;   // robots that refused or did not answer, and why
  std::string text;                   // the decision and its reasons, then the robots
};

// What a caller is doing with the client's buses, for a reader beside it that must not disturb the
// work (web::FpsClientPage): nothing that minds other traffic; a move (it polls the status words
// itself, positions may still be read); work no other traffic may meet (a trajectory upload, a
// discovery, which replaces the robots' handles, a firmware upgrade, a measurement).
enum class BusUse { shared, moving, exclusive };

class Client {
 public:
  explicit Client(ClientConfig config = {});
  ~Client();  // close(), never throws
  Client(const Client&) = delete;
  Client& operator=(const Client&) = delete;

  // Opens buses by spec ("cannet://HOST:PORT/N", "socketcand://HOST:PORT/can0", "socketcan:can0").
  // plan_and_move() then needs a layout (set_layout).
  void open(const std::vector<std::string>& bus_specs);
  // Opens every gateway of a layout (one CAN@net connection each, the channels its robots use),
  // each at its layout address or, when given, at gateway_addresses[id] ("HOST:PORT").
  void open(const FocalPlane& plane, const std::map<std::uint16_t, std::string>& gateway_addresses = {});
  // The layout plan_and_move() plans on (set by open(plane)).
  void set_layout(const FocalPlane& plane);
  [[nodiscard]] bool is_open() const noexcept;
  // The bound of each later blocking call (ClientConfig::call_timeout_s).
  void set_call_timeout(double seconds);

  // GET_ID on every bus, then firmware and status of every robot found.
  std::vector<RobotStatus> discover();
  // Firmware, status and position of every known robot (discover() first).
  std::vector<RobotStatus> status();
  [[nodiscard]] std::vector<std::uint16_t> robots() const;

  // Moves the listed robots at once (GO_TO_ABSOLUTE_POSITION) and waits for them.
  MoveOutcome goto_absolute(const std::map<std::uint16_t, Angles>& targets);
  // Uploads, starts together and follows trajectories, by robot id. The start is the
  // START_TRAJECTORY broadcast, or with `by_sync_line` a pulse of the PLC's sync line (open(plane)
  // with ClientConfig::plc_address; HostErrc::invalid_argument otherwise, before anything is sent).
  MoveOutcome run_trajectories(const std::map<std::uint16_t, ArmPath>& paths, bool by_sync_line = false);
  // Plans collision-free moves from where every robot of the layout is to the targets (robots not
  // listed: folded), then runs them (docs/fps-plan.md). Throws when the plan cannot be used.
  PlanAndMoveOutcome plan_and_move(const std::map<std::uint16_t, Angles>& targets, const PlanSettings& settings = {});
  // The same with a target file (YAML or CSV: robot, alpha/beta or x/y and fibre).
  PlanAndMoveOutcome plan_and_move(const std::string& target_file, const PlanSettings& settings = {});

  // Datum search of one robot found by discover(): both arms drive into their hard stops. With a
  // layout (open(plane) or set_layout()), the positions of the robot and its neighbours are read
  // first and the way to the stops (both arms at the same speed, the stops up to 10 deg below the
  // limits) must be clear of the neighbours and the fixed obstacles: otherwise HostErrc::not_ready
  // naming what is in the way, and nothing moves (host/datum_check.hpp). Without a layout nothing
  // is checked. Waits for the end and returns where the robot then stands. Refused while locked
  // (HostErrc::locked); a robot that does not finish within the positioner's datum timeout is
  // aborted and the call throws.
  Angles go_to_datums(std::uint16_t id);
  // The calibration sequence of one robot found by discover() (motors, datums, cogging, save, as
  // `steps` says; the arms move; with datums, the same check as go_to_datums first). Takes minutes,
  // cogging up to 40: raise set_call_timeout() first when needed. Refused while locked
  // (HostErrc::locked).
  CalibrationOutcome calibrate(std::uint16_t id, const CalibrationSteps& steps = {});

  // Moves robots out of a contact (host/back_off.hpp): after a collision and unlock(), the robot
  // that reported it (the protocol document's 2 degrees away, 9.4.1); with no ids, every robot in
  // contact at the full collision buffer, as a power loss mid-move can leave them. One arm of one
  // robot at a time, each move certified against the neighbours' read positions; what could not be
  // moved is in the outcome with the reason. Needs the layout (HostErrc::invalid_argument); refused
  // while locked (HostErrc::locked).
  BackOffOutcome back_off(const std::vector<std::uint16_t>& ids = {});

  // Troubleshooting false collisions (host/troubleshoot.hpp; the interface document's 9.4.2 and
  // 9.4.3). Both need the layout (HostErrc::invalid_argument): every test move (one arm, a few
  // degrees and back) is proven clear of the neighbours' read positions first, and a robot with no
  // room is not tested. Refused while locked (HostErrc::locked); a collision during a test move
  // locks the array as any collision does.
  //
  // The friction trend of the listed robots (empty: every robot found): current against motor
  // speed fitted per arm, judged against the arm's first record in `history_file` (a CSV file, read
  // when it exists; the new records are appended to it; "" keeps no history, so every arm is a
  // baseline). Robots that are not neighbours are measured at the same time.
  host::FrictionReport friction_survey(const std::vector<std::uint16_t>& ids = {}, host::FrictionOptions options = {},
                                       const std::string& history_file = "");
  // The hall sensor and motor test of one robot, arm by arm, in open loop without collision
  // detection; closed loop with detection is restored afterwards (HallFinding::restored).
  host::HallTestReport hall_test(std::uint16_t id, const host::HallTestOptions& options = {});

  // GET_ID on every bus of the layout at once, the answers compared with the layout: robots missing,
  // on the wrong bus, unexpected or answering twice (fps/layout/layout_check.hpp). Needs
  // open(plane) (HostErrc::invalid_argument).
  LayoutCheck check_layout();
  // The cold-temperature policy once (host/cold_control.hpp): the PLC's temperatures decide every
  // robot's speed and holding currents, which are sent to all of them. Needs open(plane) with
  // ClientConfig::plc_address (HostErrc::invalid_argument); a PLC that does not answer throws.
  ColdOutcome apply_cold_policy();

  // Firmware of every robot of the layout, sextant by sextant through the PLC (host/plane_upgrade.hpp):
  // each sextant power-cycled into the bootloader, its robots sent the image at once, failures
  // retried, powered back into the application and every version read; the cold policy applied
  // again at the end. Needs open(plane) with ClientConfig::plc_address (HostErrc::invalid_argument
  // otherwise, nothing switched). `progress` is called on the client's thread (keep it short). A
  // whole plane takes minutes: raise set_call_timeout() first (600 s by default).
  FirmwareOutcome upgrade_firmware(const std::vector<std::uint8_t>& image, const UpgradeSettings& settings = {},
                                  const std::function<void(const SextantUpgrade&)>& progress = {});

  // Locks the array and aborts every robot on every bus; moves are refused until unlock().
  StopOutcome emergency_stop(const std::string& reason = "emergency stop");
  // TRAJECTORY_ABORT on every bus, without locking (with clear_flags: STOP_TRAJECTORY, which also
  // clears collision flags).
  void stop(bool clear_flags = false);
  // STOP_TRAJECTORY on every bus (clears collision flags), then unlocks.
  UnlockOutcome unlock();
  [[nodiscard]] bool locked() const;
  [[nodiscard]] std::string lock_reason() const;  // empty when not locked

  // From any thread, without waiting (a signal's watcher, a watchdog, Python's Ctrl-C): locks the
  // array for `reason` and aborts every robot on every bus, as emergency_stop() does. The call
  // waiting on the client's loop, if any, then ends soon (its moves fail as locked). Nothing
  // happens when the client is not open. Never throws.
  void interrupt(const std::string& reason) noexcept;

  // For code that works beside the blocking calls on the client's own loop thread (a web view
  // reading the robots between and during calls, web::FpsClientPage): runs f there with the focal
  // plane array (nullptr unless open(plane); it lives until close()) and the loop's io_context, and
  // waits for it. What f starts on the loop must be over before close(). f must not call the client.
  void with_loop(const std::function<void(host::FocalPlaneArray*, boost::asio::io_context&)>& f);

  // Stops what this client set moving, closes the connections. Idempotent, never throws.
  void close() noexcept;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace axon::fps
