// Layouts by name: the shipped ones resolve with and without the data folder, and the built-in
// benchtop and the generated default are the shipped files.
#include "axon/fps/layout/layout_file.hpp"
#include "axon/fps/layout/layout_name.hpp"

#include <gtest/gtest.h>

#include <string>

namespace axon::fps {
namespace {

const std::string kData = std::string(AXON_TESTS_DIR) + "/../data";

TEST(LayoutName, BuiltInBenchtopIsTheShippedFile) {
  const auto built_in = resolve_layout("benchtop").value();
  const auto shipped = resolve_layout("benchtop", kData).value();
  EXPECT_EQ(to_yaml(built_in), to_yaml(shipped));
  EXPECT_EQ(built_in.robots().size(), 6u);
}

// A program using the library without the data folder gets the same 500-robot plane as the CLI,
// which reads data/layouts/default.yaml.
TEST(LayoutName, DefaultIsGeneratedWithoutTheDataFolderAndIsTheShippedFile) {
  const auto plane = resolve_layout("default").value();
  EXPECT_EQ(plane.robots().size(), 500u);
  EXPECT_EQ(plane.gateways().size(), 6u);
  EXPECT_EQ(to_yaml(plane), to_yaml(resolve_layout("default", kData).value()));
}

TEST(LayoutName, AFilePathLoadsThatFile) {
  const auto plane = resolve_layout(kData + "/layouts/benchtop.yaml").value();
  EXPECT_EQ(plane.name(), "benchtop");
}

TEST(LayoutName, AnUnknownNameIsAnError) {
  const auto r = resolve_layout("no-such-layout");
  ASSERT_FALSE(r.has_value());
  EXPECT_EQ(r.error().code, CoreErrc::invalid_argument);
  EXPECT_NE(r.error().detail.find("no-such-layout"), std::string::npos);
}

TEST(LayoutName, GatewayAddressesAreReplacedByIdOnly) {
  const auto plane = resolve_layout("default").value();
  const auto moved = with_gateway_addresses(plane, {{2, "127.0.0.1:5000"}}).value();
  for (const auto& g : moved.gateways()) {
    if (g.id == 2) EXPECT_EQ(g.address, "127.0.0.1:5000");
    else EXPECT_EQ(g.address, plane.gateway(g.id)->address);
  }
}

}  // namespace
}  // namespace axon::fps
