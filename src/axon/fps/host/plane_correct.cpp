#include "axon/fps/host/plane_correct.hpp"

#include "axon/fps/host/concurrent.hpp"
#include "axon/fps/host/error.hpp"

#include "axon/core/wakeup.hpp"

#include <fmt/format.h>

#include <chrono>
#include <filesystem>

namespace axon::fps::host {

std::string CorrectionRound::to_text() const {
  const double tol_um = plan.tolerance_mm * 1000;
  std::string s = fmt::format("{} {} ({}): {} robots, {} within {:g} um, {} to correct, {} unreachable, {} not "
                              "measured, {} without position; worst error {:.1f} um\n",
                              evaluate_only ? "check" : "round", round, source, plan.robots.size(), plan.count(CorrectionStatus::within_tolerance), tol_um,
                              plan.count(CorrectionStatus::move), plan.count(CorrectionStatus::unreachable),
                              plan.count(CorrectionStatus::not_measured), plan.count(CorrectionStatus::no_position),
                              plan.worst_error_mm() * 1000);
  for (const auto& r : plan.robots) {
    s += fmt::format("  robot {}: ", r.robot);
    if (r.measured)
      s += fmt::format("error {:.1f} um (dx {:+.4f} dy {:+.4f} mm); ", r.error_mm * 1000, r.error.x, r.error.y);
    switch (r.status) {
      case CorrectionStatus::within_tolerance:
        s += "within tolerance, left alone";
        break;
      case CorrectionStatus::move: {
        s += fmt::format("correction alpha {:+.6f} beta {:+.6f} deg ({} elbow) -> alpha {:.6f} beta {:.6f}: ",
                         r.delta.alpha_deg, r.delta.beta_deg, plan::to_string(r.elbow), r.command.alpha_deg,
                         r.command.beta_deg);
        const auto it = results.find(r.robot);
        s += it == results.end() ? std::string("not sent") : it->second;
        break;
      }
      default:
        s += fmt::format("{}: {}", to_string(r.status), r.detail);
    }
    s += "\n";
  }
  for (const auto& n : plan.notes) s += "  note: " + n + "\n";
  return s;
}

asio::awaitable<Result<CorrectionRound>> correction_round(Array& array, const plan::CollisionModel& model,
                                                          std::span<const plan::Target> targets,
                                                          const MeasurementSet& measured,
                                                          const CorrectionOptions& options, int round, bool send) {
  if (array.locked())
    co_return make_error(HostErrc::locked, fmt::format("correction round {}: {}", round, array.lock_state().reason));
  CorrectionRound out;
  out.round = round;
  out.source = measured.source;
  out.evaluate_only = !send;

  // The commanded angles of every targeted robot the array knows, read at once.
  std::vector<std::int32_t> ids;
  for (const auto& t : targets)
    if (t.robot > 0 && t.robot <= 2047 && array.find(static_cast<std::uint16_t>(t.robot))) ids.push_back(t.robot);
  std::vector<std::optional<plan::Pose>> poses(ids.size());
  std::map<std::int32_t, std::string> read_errors;
  co_await for_each_concurrently(ids.size(), [&](std::size_t i) -> asio::awaitable<void> {
    auto* p = array.find(static_cast<std::uint16_t>(ids[i]));
    auto r = co_await p->read_position();
    if (r) {
      poses[i] = plan::Pose{r.value().alpha, r.value().beta};
    } else {
      read_errors[ids[i]] = r.error().message();
    }
  });
  std::map<std::int32_t, plan::Pose> current;
  for (std::size_t i = 0; i < ids.size(); ++i)
    if (poses[i]) current[ids[i]] = *poses[i];

  out.plan = plan_corrections(model, targets, measured, current, options);
  for (auto& r : out.plan.robots) {
    if (r.status != CorrectionStatus::no_position) continue;
    const auto e = read_errors.find(r.robot);
    r.detail = e != read_errors.end() ? "position not read: " + e->second : std::string("not known to the array");
  }

  if (!send) {
    for (const auto& [id, pose] : out.plan.moves()) out.results[id] = "not sent (the last allowed iteration is done)";
    co_return out;
  }
  std::map<std::uint16_t, ArmAngles> moves;
  for (const auto& [id, pose] : out.plan.moves()) moves[static_cast<std::uint16_t>(id)] = {pose.alpha_deg, pose.beta_deg};
  out.sent = moves.size();
  if (moves.empty()) co_return out;
  auto moved = co_await array.goto_absolute(std::move(moves));
  if (!moved) {
    for (const auto& [id, pose] : out.plan.moves()) out.results[id] = "not sent: " + moved.error().message();
    out.sent = 0;
    co_return out;
  }
  for (const auto& [id, r] : moved.value()) {
    if (r) {
      ++out.arrived;
      out.reached[id] = r.value().reached;
      out.results[id] = fmt::format("arrived (reads alpha {:.4f} beta {:.4f})", r.value().reached.alpha,
                                    r.value().reached.beta);
    } else {
      out.results[id] = "failed: " + r.error().message();
    }
  }
  co_return out;
}

bool CorrectionRun::ok() const noexcept {
  if (stopped_by) return false;
  if (converged) return true;
  if (rounds.empty()) return false;
  const auto& last = rounds.back();
  // Not verified by a further measurement: fine only if everything that needed it was corrected.
  return !verified && last.all_arrived() && last.plan.count(CorrectionStatus::unreachable) == 0 &&
         last.plan.count(CorrectionStatus::no_position) == 0 && last.plan.count(CorrectionStatus::not_measured) == 0;
}

std::string CorrectionRun::summary() const {
  std::string s = fmt::format("correction: {} round{}, {}", rounds.size(), rounds.size() == 1 ? "" : "s", end);
  if (stopped_by) s += ": " + stopped_by->message();
  return s + "\n";
}

asio::awaitable<CorrectionRun> correct_positions(Array& array, const plan::CollisionModel& model,
                                                 std::vector<plan::Target> targets, MeasurementSource next,
                                                 CorrectionRunOptions options) {
  CorrectionRun run;
  int corrections = 0;
  for (int round = 1;; ++round) {
    auto m = co_await next(round);
    if (!m) {
      run.stopped_by = m.error();
      run.end = fmt::format("stopped: no measurement for round {}", round);
      break;
    }
    if (!m.value()) {
      run.verified = false;
      run.end = round == 1 ? "no measurement given"
                           : fmt::format("{} correction{} sent, no measurement after the last one (not verified)",
                                         corrections, corrections == 1 ? "" : "s");
      break;
    }
    run.verified = true;
    const bool send = corrections < options.iterations;
    auto r = co_await correction_round(array, model, targets, *m.value(), options.correction, round, send);
    if (!r) {
      run.stopped_by = r.error();
      run.end = fmt::format("stopped in round {}", round);
      break;
    }
    run.rounds.push_back(std::move(r).value());
    const CorrectionRound& last = run.rounds.back();
    if (options.on_round) options.on_round(last);
    const std::string after = fmt::format("{} correction{}", corrections, corrections == 1 ? "" : "s");
    if (last.plan.converged()) {
      run.converged = true;
      run.end = fmt::format("every robot within {:g} um after {}", options.correction.tolerance_mm * 1000, after);
      break;
    }
    if (!send) {
      run.end = fmt::format("{} still outside {:g} um after {} (the most allowed)",
                            last.plan.robots.size() - last.plan.count(CorrectionStatus::within_tolerance),
                            options.correction.tolerance_mm * 1000, after);
      break;
    }
    if (last.sent == 0) {
      run.end = "nothing left that can be corrected";
      break;
    }
    ++corrections;
    run.verified = false;
  }
  co_return run;
}

asio::awaitable<Result<void>> wait_for_file(const std::string& path, double wait_s,
                                            const std::function<void(const std::string&)>& on_waiting) {
  namespace fs = std::filesystem;
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(wait_s);
  bool told = false;
  std::optional<std::uintmax_t> last;
  for (;;) {
    std::error_code ec;
    if (fs::exists(path, ec)) {
      const auto size = fs::file_size(path, ec);
      if (!ec && last && *last == size) co_return ok();
      last = ec ? std::nullopt : std::optional<std::uintmax_t>(size);
    } else if (!told) {
      if (on_waiting) on_waiting(path);
      told = true;
    }
    if (std::chrono::steady_clock::now() >= until)
      co_return Error(CoreErrc::invalid_argument, fmt::format("{}: not there after {:g} s", path, wait_s));
    co_await core::sleep_for(std::chrono::milliseconds(100));
  }
}

MeasurementSource measurement_files(std::vector<std::string> files, std::vector<std::int32_t> known_robots,
                                    double wait_s, std::function<void(const std::string&)> on_waiting) {
  return [files = std::move(files), known = std::move(known_robots), wait_s,
          on_waiting = std::move(on_waiting)](int round) -> asio::awaitable<Result<std::optional<MeasurementSet>>> {
    if (round < 1 || round > static_cast<int>(files.size())) co_return std::optional<MeasurementSet>();
    const std::string path = files[static_cast<std::size_t>(round - 1)];
    if (round > 1) {  // the first measurement is there already; later ones follow the moves
      auto there = co_await wait_for_file(path, wait_s, on_waiting);
      if (!there) co_return there.error();
    }
    auto m = load_measurements(path, known);
    if (!m) co_return m.error();
    co_return std::optional<MeasurementSet>(std::move(m).value());
  };
}

}  // namespace axon::fps::host
