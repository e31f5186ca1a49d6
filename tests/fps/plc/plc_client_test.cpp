// The PLC client against the emulator over loopback Modbus TCP.
#include "axon/fps/plc/client.hpp"
#include "axon/fps/plc/emulator.hpp"
#include "axon/fps/plc/error.hpp"

#include <boost/asio/executor_work_guard.hpp>
#include <boost/asio/io_context.hpp>
#include <gtest/gtest.h>

#include <condition_variable>
#include <mutex>
#include <regex>

namespace axon::fps::plc {
namespace {

std::unique_ptr<PlcEmulator> emulator(EmulatorOptions o = {}) {
  auto e = PlcEmulator::start(std::move(o));
  EXPECT_TRUE(e.has_value()) << e.error().message();
  return std::move(e).value();
}

// Collects relay events from the server thread.
struct EventLog {
  std::mutex mu;
  std::condition_variable cv;
  std::vector<RelayEvent> events;
  void operator()(const RelayEvent& e) {
    std::lock_guard lock(mu);
    events.push_back(e);
    cv.notify_all();
  }
  // Hooks run on the server thread right after the reply went out: wait for them (the limit
  // only keeps a broken emulator from hanging the test).
  std::vector<RelayEvent> wait_for(std::size_t n) {
    std::unique_lock lock(mu);
    cv.wait_for(lock, std::chrono::seconds(5), [&] { return events.size() >= n; });
    return events;
  }
};

TEST(PlcClient, StatusReadsDefaultStateOfEveryRelayAndSensor) {
  auto emu = emulator();
  ASSERT_NE(emu->port(), 0);
  PlcClient client(emu->endpoint());
  auto s = client.status();
  ASSERT_TRUE(s.has_value()) << s.error().message();
  for (bool on : s.value().positioner_power) EXPECT_TRUE(on);
  for (bool on : s.value().gateway_power) EXPECT_TRUE(on);
  EXPECT_FALSE(s.value().sync_line);
  ASSERT_EQ(s.value().temperatures.size(), 6u);
  EXPECT_EQ(s.value().temperatures[0].name, "fps_plate_centre");
  EXPECT_NEAR(*s.value().temperatures[0].value, 15.0, 1e-9);
  EXPECT_NEAR(*s.value().humidity.value, 35.0, 1e-9);
  EXPECT_NEAR(*s.value().pressure.value, 780.0, 1e-9);
  EXPECT_NEAR(*s.value().coolant_flow.value, 4.0, 1e-9);
  EXPECT_TRUE(std::regex_search(s.value().to_text(), std::regex("\nsync line +low\n"))) << s.value().to_text();
}

TEST(PlcClient, RelayWritesChangeTheEmulatorAndFireHooksOncePerChange) {
  auto emu = emulator();
  EventLog log;
  emu->on_relay_change([&](const RelayEvent& e) { log(e); });
  PlcClient client(emu->endpoint());
  ASSERT_TRUE(client.set_positioner_power(3, false).has_value());
  ASSERT_TRUE(client.set_positioner_power(3, false).has_value());  // no change: no event
  ASSERT_TRUE(client.set_gateway_power(6, false).has_value());
  ASSERT_TRUE(client.set_sync_line(true).has_value());
  const auto events = log.wait_for(3);
  ASSERT_EQ(events.size(), 3u);
  EXPECT_EQ(events[0].relay, (Relay{RelayKind::positioner_power, 3}));
  EXPECT_FALSE(events[0].on);
  EXPECT_EQ(events[0].coil, 2);
  EXPECT_EQ(events[1].relay, (Relay{RelayKind::gateway_power, 6}));
  EXPECT_EQ(events[2].relay, (Relay{RelayKind::sync_line, 0}));
  EXPECT_TRUE(events[2].on);
  EXPECT_FALSE(emu->relay({RelayKind::positioner_power, 3}));
  EXPECT_TRUE(emu->relay({RelayKind::positioner_power, 2}));
  auto s = client.status();
  ASSERT_TRUE(s.has_value());
  EXPECT_FALSE(s.value().positioner_power[2]);
  EXPECT_FALSE(s.value().gateway_power[5]);
  EXPECT_TRUE(s.value().sync_line);
  auto r = client.relay({RelayKind::positioner_power, 3});
  ASSERT_TRUE(r.has_value());
  EXPECT_FALSE(r.value());
}

TEST(PlcClient, SyncPulseIsARisingThenFallingEdge) {
  auto emu = emulator();
  EventLog log;
  emu->on_relay_change([&](const RelayEvent& e) { log(e); });
  PlcClient client(emu->endpoint());
  ASSERT_TRUE(client.pulse_sync_line(std::chrono::milliseconds(5)).has_value());
  const auto events = log.wait_for(2);
  ASSERT_EQ(events.size(), 2u);
  EXPECT_TRUE(events[0].on);
  EXPECT_FALSE(events[1].on);
  EXPECT_FALSE(emu->relay({RelayKind::sync_line, 0}));
}

TEST(PlcClient, HooksPostToAnExecutorWhenGiven) {
  boost::asio::io_context io;
  EmulatorOptions o;
  o.hook_executor = io.get_executor();
  auto emu = emulator(o);
  std::vector<RelayEvent> seen;
  emu->on_relay_change([&](const RelayEvent& e) { seen.push_back(e); });
  PlcClient client(emu->endpoint());
  ASSERT_TRUE(client.set_positioner_power(1, false).has_value());
  EXPECT_TRUE(seen.empty());  // never run on the server thread
  auto guard = boost::asio::make_work_guard(io);
  io.run_one_for(std::chrono::seconds(5));
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_EQ(seen[0].relay, (Relay{RelayKind::positioner_power, 1}));
}

TEST(PlcClient, SensorsSetFaultyAndScripted) {
  EmulatorOptions o;
  o.script = SensorScript({{0, "coolant_return", -4.5}, {1e6, "coolant_return", 100}, {0, "humidity", 61.2}});
  auto emu = emulator(o);
  ASSERT_TRUE(emu->set_sensor("fps_plate_edge", -12.3).has_value());
  ASSERT_TRUE(emu->set_sensor_fault("ieb_air").has_value());
  EXPECT_FALSE(emu->set_sensor("no_such_sensor", 1).has_value());
  PlcClient client(emu->endpoint());
  auto t = client.temperatures();
  ASSERT_TRUE(t.has_value()) << t.error().message();
  EXPECT_NEAR(*t.value()[1].value, -12.3, 1e-9);
  EXPECT_FALSE(t.value()[2].value.has_value());
  // Scripted: starts at -4.5 and rises by 1e-4 degC per second: still -4.5 at 0.1 resolution.
  EXPECT_NEAR(*t.value()[5].value, -4.5, 1e-9);
  auto s = client.status();
  ASSERT_TRUE(s.has_value());
  EXPECT_NEAR(*s.value().humidity.value, 61.2, 1e-9);
  // A script naming an unknown sensor is refused.
  EXPECT_FALSE(emu->set_script(SensorScript({{0, "nope", 1}})).has_value());
}

TEST(PlcClient, BadAddressIsATypedErrorWithLibmodbusMessageAndKeepsTheConnection) {
  auto emu = emulator();
  PlcClient client(emu->endpoint());
  auto r = client.read_coils(1000, 1);
  ASSERT_FALSE(r.has_value());
  EXPECT_EQ(r.error(), PlcErrc::bad_address);
  EXPECT_NE(r.error().detail.find("address 1000"), std::string::npos) << r.error().detail;
  EXPECT_NE(r.error().detail.find("Illegal data address"), std::string::npos) << r.error().detail;
  auto w = client.read_input_registers(500, 2);
  EXPECT_EQ(w.error(), PlcErrc::bad_address);
  EXPECT_TRUE(client.connected());
  EXPECT_EQ(client.counters().connects, 1u);
  EXPECT_TRUE(client.status().has_value());
  EXPECT_EQ(client.set_positioner_power(7, true).error(), PlcErrc::invalid_argument);
}

TEST(PlcClient, ConnectionRefusedIsConnectFailed) {
  std::uint16_t port = 0;
  {
    auto emu = emulator();
    port = emu->port();
  }  // stopped: nothing listens there now
  PlcClientOptions o;
  o.timeout = std::chrono::milliseconds(500);
  PlcClient client(net::Endpoint{"127.0.0.1", port}, {}, o);
  auto r = client.status();
  ASSERT_FALSE(r.has_value());
  EXPECT_EQ(r.error(), PlcErrc::connect_failed);
  EXPECT_NE(r.error().detail.find("127.0.0.1"), std::string::npos) << r.error().detail;
}

TEST(PlcClient, ReconnectsAfterTheServerDroppedTheConnection) {
  EmulatorOptions o;
  auto emu = emulator(o);
  const auto port = emu->port();
  PlcClient client(emu->endpoint());
  ASSERT_TRUE(client.status().has_value());
  emu.reset();  // closes every connection
  o.port = port;
  auto again = emulator(o);
  ASSERT_TRUE(again);
  ASSERT_TRUE(client.set_gateway_power(2, false).has_value());
  EXPECT_EQ(client.counters().reconnects, 1u);
  EXPECT_FALSE(again->relay({RelayKind::gateway_power, 2}));
}

TEST(PlcClient, CustomMapFromYaml) {
  auto node = core::ConfigNode::load_string(
      "unit_id: 3\n"
      "coils: {positioner_power: [20, 21, 22, 23, 24, 25], sync_line: 30}\n"
      "input_registers:\n"
      "  temperatures: [{name: plate, address: 40}]\n"
      "  coolant_flow: {address: 7, scale: 0.1}\n",
      "map.yaml");
  ASSERT_TRUE(node.has_value());
  auto map = RegisterMap::from_config(node.value());
  ASSERT_TRUE(map.has_value()) << map.error().message();
  EXPECT_EQ(map.value().unit_id, 3);
  EXPECT_EQ(map.value().coil_of({RelayKind::positioner_power, 4}), 23);
  EXPECT_EQ(map.value().coil_of({RelayKind::gateway_power, 1}), 8);
  EXPECT_EQ(map.value().relay_at(30), (Relay{RelayKind::sync_line, 0}));
  EmulatorOptions o;
  o.map = map.value();
  auto emu = emulator(o);
  ASSERT_TRUE(emu->set_sensor("plate", -3.2).has_value());
  PlcClient client(emu->endpoint(), map.value());
  auto s = client.status();
  ASSERT_TRUE(s.has_value()) << s.error().message();
  ASSERT_EQ(s.value().temperatures.size(), 1u);
  EXPECT_NEAR(*s.value().temperatures[0].value, -3.2, 1e-9);
  ASSERT_TRUE(client.set_positioner_power(4, false).has_value());
  EXPECT_FALSE(emu->relay({RelayKind::positioner_power, 4}));
}

TEST(RegisterMap, ConflictsAndTyposAreLocatedErrors) {
  auto bad = [](const char* text) {
    auto node = core::ConfigNode::load_string(text, "map.yaml");
    EXPECT_TRUE(node.has_value());
    auto m = RegisterMap::from_config(node.value());
    EXPECT_FALSE(m.has_value());
    return m ? std::string() : m.error().detail;
  };
  EXPECT_NE(bad("coils: {sync_line: 0}\n").find("coil 0 is used by both"), std::string::npos);
  EXPECT_NE(bad("coils: {positioner_power: [1, 2]}\n").find("expected 6 coil addresses"), std::string::npos);
  EXPECT_NE(bad("input_registers: {humidity: {address: 0}}\n").find("input register 0"), std::string::npos);
  EXPECT_NE(bad("coil: {}\n").find("map.yaml:1:1"), std::string::npos);
  EXPECT_NE(bad("input_registers: {pressure: {address: 17, scale: 0}}\n").find("scale must be positive"), std::string::npos);
}

TEST(AnalogInput, EncodingRoundTripsAndFaultValue) {
  AnalogInput t{"t", 0, 0.1, true, "degC"};
  EXPECT_EQ(t.encode(-12.3), static_cast<std::uint16_t>(static_cast<std::int16_t>(-123)));
  EXPECT_NEAR(*t.decode(t.encode(-12.3)), -12.3, 1e-9);
  EXPECT_FALSE(t.decode(0x8000).has_value());
  EXPECT_EQ(t.encode(std::nullopt), 0x8000);
  EXPECT_NEAR(*t.decode(t.encode(1e9)), 3276.7, 1e-9);  // clamped, never the fault value
  AnalogInput h{"h", 0, 0.1, false, "%"};
  EXPECT_NEAR(*h.decode(h.encode(-5)), 0.0, 1e-9);
  EXPECT_FALSE(h.decode(0xFFFF).has_value());
}

TEST(SensorScript, InterpolatesHoldsAndLeavesUnscriptedAlone) {
  SensorScript s({{10, "a", 0}, {20, "a", -10}, {0, "b", 5}});
  EXPECT_TRUE(s.values_at(5).count("a") == 0);
  EXPECT_NEAR(s.values_at(5).at("b"), 5, 1e-12);
  EXPECT_NEAR(s.values_at(10).at("a"), 0, 1e-12);
  EXPECT_NEAR(s.values_at(15).at("a"), -5, 1e-12);
  EXPECT_NEAR(s.values_at(25).at("a"), -10, 1e-12);
}

}  // namespace
}  // namespace axon::fps::plc
