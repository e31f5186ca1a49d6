// `axon fps plane ...`: the whole focal plane of a layout at once (every gateway, every bus, the
// PLC): layout check, status of every robot, a coordinated move of every robot started by
// broadcast or by the sync line, firmware upgrade, the cold policy and correction iterations after
// a measurement of the fibres.
#include "commands.hpp"
#include "fps/host/focal_plane_array.hpp"
#include "fps/host/cold_control.hpp"
#include "fps/host/plane_correct.hpp"
#include "fps/host/plane_upgrade.hpp"
#include "fps/plan/layout_model.hpp"
#include "layout_name.hpp"
#include "net/endpoint.hpp"
#include "run.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>

namespace axon::app {
namespace {

namespace host = fps::host;
namespace protocol = fps::protocol;

struct PlaneArgs {
  std::string layout;
  std::string plc;
  double window_s = 0.5;
  double alpha = 0;
  double beta = 180;
  double duration_s = 10;
  int points = 20;
  bool sync = false;
  std::string image;              // upgrade
  std::string version;            // upgrade: expected version
  std::vector<int> sextants;      // upgrade
  double power_off_s = 1.0;       // upgrade
  bool watch = false;             // cold
  double period_s = 60;           // cold --watch
  double for_s = 0;               // cold --watch: 0 until a signal
  std::string targets;            // correct
  std::vector<std::string> measured;  // correct: one file per round
  double tolerance_um = 5;        // correct
  int iterations = 3;             // correct
  double wait_s = 600;            // correct: for each measurement file to appear
};


// Waits (polling) until `path` exists and its size stays the same over two polls (a file still
// being written is not read), for at most `wait_s` seconds.
asio::awaitable<Result<void>> wait_for_file(const std::string& path, double wait_s) {
  namespace fs = std::filesystem;
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(wait_s);
  bool told = false;
  std::optional<std::uintmax_t> last;
  for (;;) {
    std::error_code ec;
    const bool there = fs::exists(path, ec);
    if (there) {
      const auto size = fs::file_size(path, ec);
      if (!ec && last && *last == size) co_return ok();
      last = ec ? std::nullopt : std::optional<std::uintmax_t>(size);
    } else if (!told) {
      std::fprintf(stderr, "waiting for %s\n", path.c_str());
      std::fflush(stderr);
      told = true;
    }
    if (std::chrono::steady_clock::now() >= until)
      co_return Error(CoreErrc::invalid_argument, fmt::format("{}: not there after {:g} s", path, wait_s));
    co_await core::sleep_for(std::chrono::milliseconds(100));
  }
}

std::vector<std::uint8_t> read_image(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Exception(usage(fmt::format("cannot open {}", path)));
  std::vector<std::uint8_t> image((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw Exception(usage(fmt::format("cannot read {}", path)));
  return image;
}

host::FocalPlaneArrayOptions array_options(const PlaneArgs& a) {
  host::FocalPlaneArrayOptions o;
  o.check_window = std::chrono::duration_cast<core::Duration>(std::chrono::duration<double>(a.window_s));
  if (!a.plc.empty()) o.plc = need(net::parse_endpoint(a.plc, 502));
  return o;
}

int run_plane(const PlaneArgs& a, const std::string& action) {
  const auto plane = need(resolve_layout(a.layout));
  return run_command([&](asio::io_context& io, auto set_on_signal) -> asio::awaitable<int> {
    const auto ex = io.get_executor();
    std::vector<std::uint8_t> image;
    host::PlaneUpgradeOptions uo;
    if (action == "upgrade") {
      image = read_image(a.image);
      if (!a.version.empty()) uo.expected_version = need(protocol::FirmwareVersion::parse(a.version));
      uo.sextants = a.sextants;
      uo.power_off_time = std::chrono::duration_cast<core::Duration>(std::chrono::duration<double>(a.power_off_s));
      uo.progress = [](const host::SextantProgress& p) {
        std::fprintf(stderr, "%s\n", p.to_text().c_str());
        std::fflush(stderr);
      };
    }
    if (action == "correct") {
      // The first measurement must be there and readable before anything is connected.
      const auto model = need(fps::plan::model_from_layout(plane));
      std::vector<std::int32_t> known;
      for (const auto& r : model.robots()) known.push_back(r.id());
      need(host::load_measurements(a.measured.at(0), known));
      need(fps::plan::load_targets(a.targets));
    }
    auto connected = co_await host::FocalPlaneArray::connect(ex, plane, array_options(a));
    auto fpa = need(std::move(connected));
    int rc = 0;
    if (action == "check") {
      const auto check = co_await fpa->check_layout();
      std::fputs(check.to_text().c_str(), stdout);
      rc = check.ok() ? 0 : 1;
    } else if (action == "status") {
      auto d = co_await fpa->discover();
      const auto found = need(std::move(d));
      std::map<std::string, int> states;
      for (const auto& row : found.table.rows) ++states[row.error.empty() ? row.state() : "no answer"];
      std::printf("%zu robots known on %zu buses\n", found.table.rows.size(), fpa->bus_count());
      for (const auto& [s, n] : states) std::printf("  %s: %d\n", s.c_str(), n);
      for (const auto& p : found.problems) std::printf("problem: %s\n", p.c_str());
      for (const auto& row : found.table.rows)
        if (!row.error.empty()) std::printf("  positioner %u: %s\n", unsigned{row.id}, row.error.c_str());
    } else if (action == "move") {
      // Every known robot from where it is straight to (alpha, beta), all with the same timing.
      const auto table = co_await fpa->array().status_table(true);
      std::map<std::uint16_t, protocol::Trajectory> t;
      for (const auto& row : table.rows) {
        if (!row.position) {
          std::printf("positioner %u: no position (%s); left out\n", unsigned{row.id}, row.error.c_str());
          continue;
        }
        std::vector<protocol::ArmPoint> al, be;
        for (int i = 1; i <= a.points; ++i) {
          const double f = static_cast<double>(i) / a.points;
          al.push_back({row.position->alpha + (a.alpha - row.position->alpha) * f, a.duration_s * f});
          be.push_back({row.position->beta + (a.beta - row.position->beta) * f, a.duration_s * f});
        }
        t.emplace(row.id, need(protocol::Trajectory::from_physical(al, be)));
      }
      auto r = co_await fpa->run_trajectories(std::move(t), {}, a.sync);
      const auto rep = need(std::move(r));
      std::map<std::size_t, std::pair<int, int>> per_bus;  // started, robots
      for (const auto& rr : rep.robots) {
        auto& c = per_bus[rr.bus];
        ++c.second;
        const bool went = rr.state == host::RobotState::started || rr.state == host::RobotState::completed ||
                          rr.state == host::RobotState::position_mismatch || rr.state == host::RobotState::timeout ||
                          rr.state == host::RobotState::stopped || rr.state == host::RobotState::collided;
        c.first += went ? 1 : 0;
      }
      for (const auto& [b, c] : per_bus)
        std::printf("bus %s: %d of %d robots started\n", fpa->bus_ref(b).to_string().c_str(), c.first, c.second);
      std::printf("start by %s; upload %.3f s, start %.3f s, move %.3f s\n", a.sync ? "the sync line" : "broadcast",
                  std::chrono::duration<double>(rep.timings.upload).count(),
                  std::chrono::duration<double>(rep.timings.start).count(),
                  std::chrono::duration<double>(rep.timings.move).count());
      const auto& lock = fpa->array().lock_state();
      if (lock.locked) std::printf("locked: %s\n", lock.reason.c_str());
      std::fputs(rep.summary().c_str(), stdout);
      rc = rep.completed ? 0 : 1;
    }
    if (action == "cold") {
      // Once, or every period until a signal (or --for): the settings go out only when they change.
      host::ColdControl cold(*fpa);
      bool stop = false;
      set_on_signal([&stop] { stop = true; });
      const auto t0 = std::chrono::steady_clock::now();
      bool first = true;
      while (!stop) {
        auto r = co_await cold.step(first);
        first = false;
        if (!r) {
          std::printf("cold policy: %s\n", r.error().message().c_str());
          rc = 1;
        } else if (r.value().sent || !a.watch) {
          std::fputs(r.value().to_text().c_str(), stdout);
          rc = r.value().failed.empty() ? 0 : 1;
        }
        std::fflush(stdout);
        if (!a.watch) break;
        const auto next = std::chrono::steady_clock::now() + std::chrono::duration<double>(a.period_s);
        while (!stop && std::chrono::steady_clock::now() < next) {
          co_await core::sleep_for(std::chrono::milliseconds(50));
          if (a.for_s > 0 && std::chrono::steady_clock::now() - t0 >= std::chrono::duration<double>(a.for_s)) stop = true;
        }
      }
      set_on_signal([] {});
    }
    if (action == "correct") {
      // Correction iterations: each round reads the next --measured file (waiting for it to appear),
      // corrects the robots outside tolerance and waits for them to arrive.
      const auto targets = need(fps::plan::load_targets(a.targets));
      const auto model = need(fps::plan::model_from_layout(plane));
      std::vector<std::int32_t> known;
      for (const auto& r : model.robots()) known.push_back(r.id());
      host::CorrectionRunOptions co;
      co.iterations = a.iterations;
      co.correction.tolerance_mm = a.tolerance_um / 1000.0;
      co.on_round = [](const host::CorrectionRound& r) {
        std::fputs(r.to_text().c_str(), stdout);
        std::fflush(stdout);
      };
      const auto files = a.measured;
      const double wait_s = a.wait_s;
      host::MeasurementSource source =
          [files, wait_s, known](int round) -> asio::awaitable<Result<std::optional<host::MeasurementSet>>> {
        if (round > static_cast<int>(files.size())) co_return std::optional<host::MeasurementSet>();
        const std::string path = files[static_cast<std::size_t>(round - 1)];
        if (round > 1) {  // the first measurement is there already; later ones follow the moves
          auto there = co_await wait_for_file(path, wait_s);
          if (!there) co_return there.error();
        }
        auto m = host::load_measurements(path, known);
        if (!m) co_return m.error();
        co_return std::optional<host::MeasurementSet>(std::move(m).value());
      };
      auto run = co_await host::correct_positions(fpa->array(), model, targets, source, co);
      const auto& lock = fpa->array().lock_state();
      if (lock.locked) std::printf("locked: %s\n", lock.reason.c_str());
      std::fputs(run.summary().c_str(), stdout);
      rc = run.ok() ? 0 : 1;
    }
    if (action == "upgrade") {
      if (!uo.expected_version) std::printf("no --version given: versions are reported, not checked\n");
      auto r = co_await host::upgrade_plane(*fpa, image, uo);
      const auto rep = need(std::move(r));
      std::fputs(rep.summary().c_str(), stdout);
      rc = rep.ok() ? 0 : 1;
    }
    std::fflush(stdout);
    co_await fpa->close();
    co_return rc;
  });
}

}  // namespace

void add_fps_plane_commands(CLI::App& app, GlobalOptions&) {
  CLI::App* fps_cmd = app.get_subcommand("fps");
  static PlaneArgs a;
  auto* p = fps_cmd->add_subcommand("plane", "the whole focal plane of a layout: every gateway and bus, and the PLC");
  p->require_subcommand(1);
  p->add_option("--layout", a.layout, "layout: default, benchtop or FILE (gateway addresses from it)")->required();
  p->add_option("--plc", a.plc, "the PLC at HOST[:PORT] (needed for --sync)");
  p->add_subcommand("check", "GET_ID on every bus at once, compared with the layout")->callback([] {
    exit_code() = run_plane(a, "check");
  });
  auto* ck = p->get_subcommand("check");
  ck->add_option("--window", a.window_s, "seconds to collect GET_ID answers (default 0.5)");
  p->add_subcommand("status", "discovery: firmware and status of every robot")->callback([] {
    exit_code() = run_plane(a, "status");
  });
  auto* mv = p->add_subcommand("move", "every robot straight to one (alpha, beta) by a trajectory, all at once");
  mv->add_option("--alpha", a.alpha, "degrees (default 0)");
  mv->add_option("--beta", a.beta, "degrees (default 180: folded)");
  mv->add_option("--duration", a.duration_s, "seconds of the trajectory (default 10)");
  mv->add_option("--points", a.points, "points per arm (default 20)")->check(CLI::Range(1, 1000));
  mv->add_flag("--sync", a.sync, "start with the PLC's sync line instead of the START_TRAJECTORY broadcast");
  mv->callback([] { exit_code() = run_plane(a, "move"); });
  auto* up = p->add_subcommand("upgrade",
                               "firmware of every robot, sextant by sextant: power-cycled into the bootloader by the PLC, "
                               "upgraded (one retry), powered back, version checked (needs --plc)");
  up->add_option("--image", a.image, "firmware image file")->required()->check(CLI::ExistingFile);
  up->add_option("--version", a.version, "version the robots must run afterwards (XX.YY.ZZ); without it, not checked");
  up->add_option("--sextant", a.sextants, "only these sextants (repeatable; default every sextant with robots)")
      ->check(CLI::Range(1, 6));
  up->add_option("--power-off", a.power_off_s, "seconds without positioner power before powering up (default 1)")
      ->check(CLI::Range(0.0, 60.0));
  auto* cd = p->add_subcommand("cold",
                               "cold-temperature policy: PLC temperatures -> speed and holding current of every robot "
                               "(needs --plc)");
  cd->add_flag("--watch", a.watch, "keep going: read every --period, send only when the decision changes");
  cd->add_option("--period", a.period_s, "seconds between readings with --watch (default 60)")->check(CLI::Range(0.05, 86400.0));
  cd->add_option("--for", a.for_s, "with --watch: stop after this many seconds (default: at a signal)");
  cd->callback([] {
    if (a.plc.empty()) throw Exception(usage("fps plane cold needs --plc"));
    exit_code() = run_plane(a, "cold");
  });
  auto* cr = p->add_subcommand("correct",
                               "correction iterations: robots whose measured fibre is outside tolerance get a correction "
                               "move (GO_TO_ABSOLUTE_POSITION), one round per --measured file");
  cr->add_option("--targets", a.targets, "target file (.yaml/.csv, docs/fps-plan.md)")->required()->check(CLI::ExistingFile);
  cr->add_option("--measured", a.measured,
                 "measured fibre positions, CSV robot,x,y[,fibre] in mm (repeatable, one per round, in order; "
                 "files after the first are waited for)")
      ->required();
  cr->add_option("--tolerance-um", a.tolerance_um, "robots closer than this to their target are left alone (default 5)")
      ->check(CLI::Range(0.0, 10000.0));
  cr->add_option("--iterations", a.iterations, "most rounds that send corrections (default 3)")->check(CLI::Range(1, 100));
  cr->add_option("--wait", a.wait_s, "seconds to wait for each later --measured file to appear (default 600)")
      ->check(CLI::Range(0.0, 86400.0));
  cr->callback([] { exit_code() = run_plane(a, "correct"); });
  up->callback([] {
    if (a.plc.empty()) throw Exception(usage("fps plane upgrade needs --plc"));
    exit_code() = run_plane(a, "upgrade");
  });
}

}  // namespace axon::app
