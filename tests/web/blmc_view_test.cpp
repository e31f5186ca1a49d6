#include "axon/web/blmc_view.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>

namespace axon::web {
namespace {

namespace host = blmc::host;
using json = nlohmann::json;
using namespace std::chrono_literals;

constexpr std::uint8_t kEnabledAndReady = 0x1F;  // system, both motors enabled and ready
constexpr std::uint8_t kEncoderError = 1u << 5;  // error code 1, every flag off

// Cycle `n` of a 1 kHz loop whose motor 1 turns at 1 rev/s (position = t) with current 0.5 A.
host::CycleRecord record(std::uint64_t n, std::uint8_t status = kEnabledAndReady, core::Duration period = 1ms) {
  host::CycleRecord r;
  r.cycle = n;
  r.start = core::TimePoint{} + std::chrono::milliseconds(n);
  r.period = n == 0 ? core::Duration{0} : period;
  r.boards = 1;
  r.board[0].current = {0.5, -0.25};
  r.board[0].position = {static_cast<double>(n) / 1000.0, 0.0};
  r.board[0].velocity = {0.06, 0.0};  // krpm
  r.board[0].status = status;
  return r;
}

BlmcViewOptions one_board() {
  BlmcViewOptions o;
  host::SafetyLimits limits;
  limits.max_current_a = 1.5;
  o.boards = {{"can0", limits}};
  o.command = "pd";
  return o;
}

TEST(BlmcView, KeepsFiftySamplesASecondOfTheLastTwelveSeconds) {
  BlmcView view(one_board());
  for (std::uint64_t n = 0; n < 3000; ++n) view.add_record(record(n));
  auto board = json::parse(view.state_json())["boards"][0];
  auto samples = board["samples"];
  EXPECT_EQ(samples["n"], 150);  // 3 s at 50 Hz
  EXPECT_NEAR(samples["t"][1].get<double>() - samples["t"][0].get<double>(), 0.02, 1.5e-3);
  // The last sample is at most one sample period behind the last record.
  EXPECT_NEAR(samples["p1"].back().get<double>(), 2.999, 0.02);
  EXPECT_DOUBLE_EQ(samples["i1"].back().get<double>(), 0.5);
  EXPECT_DOUBLE_EQ(samples["i2"].back().get<double>(), -0.25);

  for (std::uint64_t n = 3000; n < 20000; ++n) view.add_record(record(n));
  samples = json::parse(view.state_json())["boards"][0]["samples"];
  EXPECT_EQ(samples["n"], 600);  // 12 s at 50 Hz, no more
  EXPECT_EQ(samples["t"].size(), 600u);
  EXPECT_NEAR(samples["t"][0].get<double>(), 20.0 - 12.0, 0.03);
  EXPECT_NEAR(samples["t"].back().get<double>(), 19.98, 0.03);
}

TEST(BlmcView, CountsCyclesLostRecordsOverrunsAndJitter) {
  BlmcView view(one_board());
  view.add_record(record(0));
  view.add_record(record(1, kEnabledAndReady, 1003us));   // 3 us: bucket <= 5 us
  auto late = record(2, kEnabledAndReady, 1300us);       // 300 us: bucket <= 500 us
  late.overruns = 1;
  view.add_record(late);
  auto after_gap = record(5, kEnabledAndReady, 1000us);  // cycles 3 and 4 never arrived
  after_gap.overruns = 1;
  view.add_record(after_gap);
  const auto loop = json::parse(view.state_json())["loop"];
  EXPECT_EQ(loop["cycles"], 6);
  EXPECT_EQ(loop["records_lost"], 2);
  EXPECT_EQ(loop["overruns"], 1);
  EXPECT_EQ(loop["running"], true);
  EXPECT_EQ(loop["jitter"], json::parse("[2,0,0,0,0,0,1,0,0,0,0]"));
  EXPECT_NEAR(loop["jitter_max_us"].get<double>(), 300.0, 0.1);

  const auto m = view.metrics();
  EXPECT_NE(m.find("# TYPE axon_blmc_loop_jitter_seconds histogram\n"), std::string::npos) << m;
  EXPECT_NE(m.find("axon_blmc_loop_jitter_seconds_bucket{le=\"5e-06\"} 2\n"), std::string::npos) << m;
  EXPECT_NE(m.find("axon_blmc_loop_jitter_seconds_bucket{le=\"0.0005\"} 3\n"), std::string::npos) << m;
  EXPECT_NE(m.find("axon_blmc_loop_jitter_seconds_count 3\n"), std::string::npos) << m;
  EXPECT_NE(m.find("\naxon_blmc_loop_cycles_total 6\n"), std::string::npos) << m;
  EXPECT_NE(m.find("\naxon_blmc_loop_overruns_total 1\n"), std::string::npos) << m;
  EXPECT_NE(m.find("\naxon_blmc_loop_records_lost_total 2\n"), std::string::npos) << m;
}

TEST(BlmcView, ShowsTheBoardErrorItsMeaningAndTheSafetyStop) {
  BlmcView view(one_board());
  view.add_record(record(0));
  for (std::uint64_t n = 1; n < 5; ++n) view.add_record(record(n, kEncoderError));
  host::LoopStats stats;
  stats.cycles = 5;
  host::LoopFault fault;
  fault.fault.kind = host::FaultKind::board_error;
  fault.fault.board_error = blmc::protocol::ErrorCode::encoder;
  view.end_run(stats, fault);
  const auto state = json::parse(view.state_json());
  const auto& board = state["boards"][0];
  EXPECT_EQ(board["error"]["code"], 1);
  EXPECT_EQ(board["error"]["name"], "ENCODER");
  EXPECT_NE(board["error"]["meaning"].get<std::string>().find("encoder"), std::string::npos);
  EXPECT_EQ(board["errors"]["ENCODER"], 1);  // one error, however many frames carried it
  EXPECT_EQ(board["flags"]["system_enabled"], false);
  EXPECT_EQ(board["fault"]["kind"], "board_error");
  EXPECT_NE(board["fault"]["text"].get<std::string>().find("ENCODER"), std::string::npos) << board["fault"];
  EXPECT_EQ(state["loop"]["running"], false);

  const auto m = view.metrics();
  EXPECT_NE(m.find("\naxon_blmc_board_errors_total{board=\"can0\",code=\"ENCODER\"} 1\n"), std::string::npos) << m;
  EXPECT_NE(m.find("\naxon_blmc_error_code{board=\"can0\"} 1\n"), std::string::npos) << m;
  EXPECT_NE(m.find("\naxon_blmc_safety_stops_total{board=\"can0\",kind=\"board_error\"} 1\n"), std::string::npos) << m;
  EXPECT_NE(m.find("\naxon_blmc_safety_stops_total{board=\"can0\",kind=\"stale_data\"} 0\n"), std::string::npos) << m;
  EXPECT_NE(m.find("\naxon_blmc_status_flag{board=\"can0\",flag=\"system_enabled\"} 0\n"), std::string::npos) << m;
  EXPECT_NE(m.find("\naxon_blmc_limit_max_current_amperes{board=\"can0\"} 1.5\n"), std::string::npos) << m;
}

TEST(BlmcView, InfoHasTheLimitsFlagsAndEveryErrorCode) {
  BlmcView view(one_board());
  const auto info = json::parse(view.info_json());
  EXPECT_EQ(info["boards"][0]["name"], "can0");
  EXPECT_DOUBLE_EQ(info["boards"][0]["limits"]["max_current_a"].get<double>(), 1.5);
  EXPECT_EQ(info["flags"].size(), 5u);
  ASSERT_EQ(info["error_codes"].size(), 8u);
  EXPECT_EQ(info["error_codes"][2]["name"], "CAN_RECV_TIMEOUT");
  EXPECT_EQ(info["error_codes"][6]["name"], "UNDOCUMENTED_6");
  EXPECT_EQ(info["jitter_bounds_us"].size(), 10u);
}

TEST(BlmcView, MonitoringWithoutALoopHasSamplesAndNoLoop) {
  BlmcViewOptions o;
  o.boards = {{"can0", std::nullopt}};
  BlmcView view(o);
  host::Measurements m;
  m.current = {{0.1, 0.2}, {}, 1};
  m.status_byte = {0x01, {}, 1};
  view.add_measurements(0, 0.5, m);
  const auto state = json::parse(view.state_json());
  EXPECT_TRUE(state["loop"].is_null());
  EXPECT_EQ(state["boards"][0]["samples"]["i2"], json::parse("[0.2]"));
  EXPECT_EQ(state["boards"][0]["flags"]["system_enabled"], true);
  EXPECT_EQ(view.metrics().find("axon_blmc_loop_"), std::string::npos);
  EXPECT_TRUE(json::parse(view.info_json())["boards"][0]["limits"].is_null());
}

TEST(BlmcView, RefusesNoBoardsAndAZeroSampleRate) {
  EXPECT_THROW(BlmcView(BlmcViewOptions{}), Exception);
  auto o = one_board();
  o.sample_hz = 0;
  EXPECT_THROW(BlmcView{o}, Exception);
}

}  // namespace
}  // namespace axon::web
