// can::BlockingBus from a plain thread: in-process virtual media shared by name, receive timeouts,
// filters, a closed bus, and errors for bad specs and refused connections.
#include "axon/can/blocking_bus.hpp"

#include <gtest/gtest.h>

#include <string>

namespace axon::can {
namespace {

Frame frame(const char* text) { return Frame::parse(text).value(); }

TEST(BlockingBus, TwoBusesNamingOneVirtualMediumSeeEachOthersFramesButNotTheirOwn) {
  BlockingBus a("virtual:blocking0");
  BlockingBus b("virtual:blocking0");
  a.send(frame("123#DEADBEEF"));
  const auto got = b.receive(2.0);
  ASSERT_TRUE(got.has_value());
  EXPECT_EQ(*got, frame("123#DEADBEEF"));
  EXPECT_FALSE(a.receive(0.05).has_value());
  EXPECT_EQ(a.stats().frames_out, 1u);
  EXPECT_EQ(b.stats().frames_in, 1u);
}

TEST(BlockingBus, ReceiveWithoutAFrameReturnsNothingAfterItsTimeout) {
  BlockingBus a("virtual:blocking1");
  EXPECT_FALSE(a.receive(0.05).has_value());
  EXPECT_FALSE(a.receive(0).has_value());
}

TEST(BlockingBus, FiltersPassOnlyMatchingIds) {
  BlockingBus a("virtual:blocking2");
  BlockingBus b("virtual:blocking2");
  b.set_filters({Filter::parse("200:7FF").value()});
  a.send(frame("100#01"));
  a.send(frame("200#02"));
  const auto got = b.receive(2.0);
  ASSERT_TRUE(got.has_value());
  EXPECT_EQ(*got, frame("200#02"));
  EXPECT_FALSE(b.receive(0.05).has_value());
}

TEST(BlockingBus, AClosedBusRefusesSendAndReceiveAsClosed) {
  BlockingBus a("virtual:blocking3");
  a.close();
  EXPECT_EQ(a.state(), BusState::closed);
  try {
    a.send(frame("001#"));
    FAIL() << "a closed bus sent a frame";
  } catch (const Exception& e) {
    EXPECT_EQ(e.code(), CanErrc::closed);
  }
  EXPECT_THROW((void)a.receive(0.01), Exception);
}

TEST(BlockingBus, BadSpecsAndRefusedConnectionsThrowTheirCodes) {
  try {
    BlockingBus bad("nonsense://x");
    FAIL() << "a bad spec opened";
  } catch (const Exception& e) {
    EXPECT_EQ(e.code(), CanErrc::bad_spec) << e.what();
  }
  BlockingBusOptions o;
  o.connect_timeout_s = 1.0;
  EXPECT_THROW(BlockingBus("socketcand://127.0.0.1:1/can0", o), Exception);
}

}  // namespace
}  // namespace axon::can
