#include "axon/fps/plc/async_client.hpp"

namespace axon::fps::plc {

AsyncPlc::AsyncPlc(net::Endpoint endpoint, RegisterMap map, PlcClientOptions options)
    : client_(std::make_unique<PlcClient>(std::move(endpoint), std::move(map), options)) {}

AsyncPlc::~AsyncPlc() {
  pool_.join();
  client_->close();
}

boost::asio::awaitable<Result<PlcStatus>> AsyncPlc::status() {
  auto r = co_await call([](PlcClient& c) { return c.status(); });
  co_return r;
}

boost::asio::awaitable<Result<void>> AsyncPlc::set_relay(Relay relay, bool on) {
  auto r = co_await call([relay, on](PlcClient& c) { return c.set_relay(relay, on); });
  co_return r;
}

boost::asio::awaitable<Result<void>> AsyncPlc::set_positioner_power(int sextant, bool on) {
  auto r = co_await call([sextant, on](PlcClient& c) { return c.set_positioner_power(sextant, on); });
  co_return r;
}

boost::asio::awaitable<Result<void>> AsyncPlc::set_gateway_power(int sextant, bool on) {
  auto r = co_await call([sextant, on](PlcClient& c) { return c.set_gateway_power(sextant, on); });
  co_return r;
}

boost::asio::awaitable<Result<void>> AsyncPlc::pulse_sync_line(core::Duration hold) {
  auto r = co_await call([hold](PlcClient& c) { return c.pulse_sync_line(hold); });
  co_return r;
}

}  // namespace axon::fps::plc
