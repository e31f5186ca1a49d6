// Where the focal-plane simulator's gateway emulators listen: counted addresses on one port, the
// layout's own addresses, one shared address.
#include "axon/fps/layout/layout_generator.hpp"
#include "axon/fps/sim/focal_plane_sim.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

namespace axon::fps::sim {
namespace {

FocalPlane six_gateways() { return generate_layout().value(); }  // the default layout: 10.25.1.11..16:19228

TEST(GatewayBinding, AnIpv4AddressCountsUpPerGatewayOnOnePort) {
  GatewayBinding b;
  b.address = "127.0.0.11";
  b.port = 19228;
  const auto eps = gateway_endpoints(six_gateways(), b).value();
  ASSERT_EQ(eps.size(), 6u);
  int k = 11;
  for (const auto& [id, ep] : eps) {
    EXPECT_EQ(ep.host, fmt::format("127.0.0.{}", k++)) << "gateway " << id;
    EXPECT_EQ(ep.port, 19228);
  }
}

TEST(GatewayBinding, TheDefaultIsLoopbackWithAnyFreePort) {
  const auto eps = gateway_endpoints(six_gateways(), GatewayBinding{}).value();
  EXPECT_EQ(eps.begin()->second.host, "127.0.0.1");
  EXPECT_EQ(eps.rbegin()->second.host, "127.0.0.6");
  for (const auto& [id, ep] : eps) EXPECT_EQ(ep.port, 0) << "gateway " << id;
}

TEST(GatewayBinding, LayoutTakesEachGatewaysOwnAddress) {
  GatewayBinding b;
  b.address = std::string(GatewayBinding::kLayoutAddresses);
  const auto plane = six_gateways();
  const auto eps = gateway_endpoints(plane, b).value();
  for (const auto& g : plane.gateways()) EXPECT_EQ(eps.at(g.id).to_string(), g.address);
  b.port = 5000;  // the layout gives the ports too
  EXPECT_FALSE(gateway_endpoints(plane, b));
}

TEST(GatewayBinding, OneAddressForAllNeedsDistinctPorts) {
  GatewayBinding b;
  b.address = "0.0.0.0";
  const auto eps = gateway_endpoints(six_gateways(), b).value();
  for (const auto& [id, ep] : eps) EXPECT_EQ(ep.host, "0.0.0.0");
  b.port = 19228;
  const auto clash = gateway_endpoints(six_gateways(), b);
  ASSERT_FALSE(clash);
  EXPECT_NE(clash.error().message().find("share the endpoint 0.0.0.0:19228"), std::string::npos) << clash.error().message();
}

TEST(GatewayBinding, CountingBeyondTheAddressSpaceIsAnError) {
  GatewayBinding b;
  b.address = "255.255.255.253";
  EXPECT_FALSE(gateway_endpoints(six_gateways(), b));
}

TEST(GatewayBinding, PerGatewayPortsWin) {
  GatewayBinding b;
  b.port = 5000;
  b.ports = {{1, 6001}};
  const auto eps = gateway_endpoints(six_gateways(), b).value();
  EXPECT_EQ(eps.at(1).port, 6001);
  EXPECT_EQ(eps.at(2).port, 5000);
}

}  // namespace
}  // namespace axon::fps::sim
