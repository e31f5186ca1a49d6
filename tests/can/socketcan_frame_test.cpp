// The struct can_frame codec, checked against records built with the kernel's own header.
#include "axon/can/socketcan_frame.hpp"

#include <gtest/gtest.h>
#include <linux/can.h>
#include <linux/can/error.h>

#include <array>
#include <cstring>
#include <vector>

using axon::can::BusState;
using axon::can::CanErrc;
using axon::can::Filter;
using axon::can::Frame;
using axon::can::IdFormat;
namespace sc = axon::can::socketcan;

namespace {

std::vector<std::uint8_t> bytes_of(const struct can_frame& cf) {
  std::vector<std::uint8_t> out(sizeof cf);
  std::memcpy(out.data(), &cf, sizeof cf);
  return out;
}

struct can_frame kernel_frame(canid_t id, std::initializer_list<std::uint8_t> data, std::uint8_t len = 0xFF) {
  struct can_frame cf {};
  cf.can_id = id;
  cf.len = len == 0xFF ? static_cast<std::uint8_t>(data.size()) : len;
  std::copy(data.begin(), data.end(), cf.data);
  return cf;
}

Frame decode_frame(const struct can_frame& cf) {
  auto d = sc::decode(bytes_of(cf));
  EXPECT_TRUE(d) << d.error().message();
  EXPECT_TRUE(std::holds_alternative<Frame>(d.value()));
  return std::get<Frame>(d.value());
}

sc::ErrorReport decode_report(const struct can_frame& cf) {
  auto d = sc::decode(bytes_of(cf));
  EXPECT_TRUE(d) << d.error().message();
  EXPECT_TRUE(std::holds_alternative<sc::ErrorReport>(d.value()));
  return std::get<sc::ErrorReport>(d.value());
}

}  // namespace

TEST(SocketCanFrame, EncodesStandardExtendedAndRemoteLikeTheKernel) {
  const std::array<std::uint8_t, 3> d{0xDE, 0xAD, 0xBE};
  auto rec = sc::encode(Frame::standard(0x123, d).value());
  EXPECT_EQ(std::vector<std::uint8_t>(rec.begin(), rec.end()), bytes_of(kernel_frame(0x123, {0xDE, 0xAD, 0xBE})));

  const std::array<std::uint8_t, 8> eight{1, 2, 3, 4, 5, 6, 7, 8};
  rec = sc::encode(Frame::extended(0x12345678, eight).value());
  EXPECT_EQ(std::vector<std::uint8_t>(rec.begin(), rec.end()),
            bytes_of(kernel_frame(0x12345678 | CAN_EFF_FLAG, {1, 2, 3, 4, 5, 6, 7, 8})));

  rec = sc::encode(Frame::remote(0x7FF, IdFormat::standard, 4).value());
  EXPECT_EQ(std::vector<std::uint8_t>(rec.begin(), rec.end()), bytes_of(kernel_frame(0x7FF | CAN_RTR_FLAG, {}, 4)));

  rec = sc::encode(Frame::remote(0x1FFFFFFF, IdFormat::extended, 0).value());
  EXPECT_EQ(std::vector<std::uint8_t>(rec.begin(), rec.end()),
            bytes_of(kernel_frame(0x1FFFFFFF | CAN_EFF_FLAG | CAN_RTR_FLAG, {}, 0)));

  // A frame with id 0 and no data is all zeros: nothing left over from earlier frames.
  rec = sc::encode(Frame());
  EXPECT_EQ(std::vector<std::uint8_t>(rec.begin(), rec.end()), std::vector<std::uint8_t>(16, 0));
}

TEST(SocketCanFrame, DecodesKernelRecords) {
  auto f = decode_frame(kernel_frame(0x123, {0x11, 0x22}));
  EXPECT_EQ(f.id(), 0x123u);
  EXPECT_FALSE(f.is_extended());
  EXPECT_FALSE(f.is_remote());
  ASSERT_EQ(f.payload().size(), 2u);
  EXPECT_EQ(f.payload()[1], 0x22);

  f = decode_frame(kernel_frame(0x00000123 | CAN_EFF_FLAG, {}));
  EXPECT_TRUE(f.is_extended());
  EXPECT_EQ(f.id(), 0x123u);
  EXPECT_EQ(f.dlc(), 0);

  f = decode_frame(kernel_frame(0x1ABCDEF0 | CAN_EFF_FLAG | CAN_RTR_FLAG, {0xAA, 0xBB}, 6));
  EXPECT_TRUE(f.is_remote());
  EXPECT_EQ(f.dlc(), 6);
  EXPECT_TRUE(f.payload().empty());  // remote frames carry no data whatever the buffer holds
}

TEST(SocketCanFrame, IgnoresBytesBeyondTheLengthAndTheRawDlc) {
  auto cf = kernel_frame(0x100, {1, 2, 3, 4, 5, 6, 7, 8}, 2);
  EXPECT_EQ(decode_frame(cf), Frame::standard(0x100, std::array<std::uint8_t, 2>{1, 2}).value());
  cf = kernel_frame(0x100, {1, 2, 3, 4, 5, 6, 7, 8});
  cf.len8_dlc = 12;  // 8-byte frame sent with raw DLC 12: still 8 bytes
  EXPECT_EQ(decode_frame(cf).dlc(), 8);
}

TEST(SocketCanFrame, RoundTrips) {
  const std::array<std::uint8_t, 8> d{0, 0xFF, 0x80, 0x7F, 1, 2, 3, 4};
  std::vector<Frame> frames;
  for (std::size_t n = 0; n <= 8; ++n) {
    frames.push_back(Frame::standard(0x7FF - n, std::span(d).first(n)).value());
    frames.push_back(Frame::extended(0x1FFFFFFF - n, std::span(d).first(n)).value());
    frames.push_back(Frame::remote(static_cast<std::uint32_t>(n), IdFormat::standard, static_cast<std::uint8_t>(n)).value());
    frames.push_back(Frame::remote(0x10000 + n, IdFormat::extended, static_cast<std::uint8_t>(n)).value());
  }
  for (const Frame& f : frames) {
    const auto rec = sc::encode(f);
    auto back = sc::decode(rec);
    ASSERT_TRUE(back) << f.to_string();
    ASSERT_TRUE(std::holds_alternative<Frame>(back.value()));
    EXPECT_EQ(std::get<Frame>(back.value()), f) << f.to_string();
    EXPECT_EQ(std::get<Frame>(back.value()).to_string(), f.to_string());
  }
}

TEST(SocketCanFrame, RejectsBadRecordsWithTypedErrors) {
  const auto good = bytes_of(kernel_frame(0x123, {1}));
  for (std::size_t size : {0u, 1u, 8u, 15u, 17u, 24u, 64u}) {
    std::vector<std::uint8_t> rec(size, 0);
    std::copy_n(good.begin(), std::min(size, good.size()), rec.begin());
    auto r = sc::decode(rec);
    ASSERT_FALSE(r) << size;
    EXPECT_EQ(r.error(), CanErrc::invalid_length) << size;
  }
  // A CAN FD record: a typed "not supported", not a size error.
  std::vector<std::uint8_t> fd(sizeof(struct canfd_frame), 0);
  auto r = sc::decode(fd);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error(), CanErrc::not_supported);

  auto cf = kernel_frame(0x123, {1, 2, 3, 4, 5, 6, 7, 8}, 9);
  r = sc::decode(bytes_of(cf));
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error(), CanErrc::invalid_length);
  cf.len = 15;
  EXPECT_EQ(sc::decode(bytes_of(cf)).error(), CanErrc::invalid_length);
  cf.can_id = CAN_ERR_FLAG | CAN_ERR_BUSOFF;  // error reports are length-checked too
  EXPECT_EQ(sc::decode(bytes_of(cf)).error(), CanErrc::invalid_length);

  // A standard-format record whose id does not fit 11 bits.
  EXPECT_EQ(sc::decode(bytes_of(kernel_frame(0x800, {}))).error(), CanErrc::invalid_id);
}

TEST(SocketCanFrame, ErrorReportsAreNotFrames) {
  auto cf = kernel_frame(CAN_ERR_FLAG | CAN_ERR_BUSOFF, {0, 0, 0, 0, 0, 0, 0, 0});
  auto rep = decode_report(cf);
  EXPECT_TRUE(rep.has(sc::ErrorClass::bus_off));
  EXPECT_EQ(rep.state(), BusState::bus_off);
  EXPECT_NE(rep.describe().find("bus-off"), std::string::npos);

  // Extended and remote flags next to the error flag do not turn it into a frame.
  cf.can_id |= CAN_EFF_FLAG | CAN_RTR_FLAG;
  EXPECT_EQ(decode_report(cf).state(), BusState::bus_off);
}

TEST(SocketCanFrame, ErrorReportStates) {
  auto state_of = [](canid_t classes, std::uint8_t ctrl) {
    return decode_report(kernel_frame(CAN_ERR_FLAG | classes, {0, ctrl, 0, 0, 0, 0, 0, 0})).state();
  };
  EXPECT_EQ(state_of(CAN_ERR_CRTL, CAN_ERR_CRTL_RX_WARNING), BusState::error_warning);
  EXPECT_EQ(state_of(CAN_ERR_CRTL, CAN_ERR_CRTL_TX_WARNING), BusState::error_warning);
  EXPECT_EQ(state_of(CAN_ERR_CRTL, CAN_ERR_CRTL_TX_PASSIVE), BusState::error_passive);
  EXPECT_EQ(state_of(CAN_ERR_CRTL, CAN_ERR_CRTL_RX_WARNING | CAN_ERR_CRTL_RX_PASSIVE), BusState::error_passive);
  EXPECT_EQ(state_of(CAN_ERR_CRTL, CAN_ERR_CRTL_ACTIVE), BusState::active);
  EXPECT_EQ(state_of(CAN_ERR_RESTARTED, 0), BusState::active);
  EXPECT_EQ(state_of(CAN_ERR_BUSOFF | CAN_ERR_CRTL, CAN_ERR_CRTL_TX_WARNING), BusState::bus_off);
  // Reports that say nothing about the controller state.
  EXPECT_EQ(state_of(CAN_ERR_LOSTARB, 0), std::nullopt);
  EXPECT_EQ(state_of(CAN_ERR_ACK | CAN_ERR_BUSERROR, 0), std::nullopt);
  EXPECT_EQ(state_of(CAN_ERR_CRTL, CAN_ERR_CRTL_RX_OVERFLOW), std::nullopt);
  // The controller bits mean nothing without the controller class.
  EXPECT_EQ(state_of(CAN_ERR_PROT, CAN_ERR_CRTL_TX_PASSIVE), std::nullopt);
}

TEST(SocketCanFrame, ErrorReportDetails) {
  auto rep = decode_report(kernel_frame(CAN_ERR_FLAG | CAN_ERR_CRTL | 0x200 /* CAN_ERR_CNT */ | CAN_ERR_LOSTARB,
                                        {5, CAN_ERR_CRTL_RX_OVERFLOW | CAN_ERR_CRTL_TX_OVERFLOW, 0, 0, 0, 0, 97, 130}));
  EXPECT_TRUE(rep.controller_rx_overflow());
  EXPECT_TRUE(rep.controller_tx_overflow());
  EXPECT_EQ(rep.tx_error_counter(), 97);
  EXPECT_EQ(rep.rx_error_counter(), 130);
  EXPECT_NE(rep.describe().find("lost arbitration at bit 5"), std::string::npos) << rep.describe();
  EXPECT_NE(rep.describe().find("tx=97 rx=130"), std::string::npos) << rep.describe();

  auto plain = decode_report(kernel_frame(CAN_ERR_FLAG | CAN_ERR_ACK, {0, 0, 0, 0, 0, 0, 9, 9}));
  EXPECT_EQ(plain.tx_error_counter(), std::nullopt);  // counters only with their class
  EXPECT_FALSE(plain.controller_rx_overflow());
}

TEST(SocketCanFrame, EncodesErrorReportsForSimulators) {
  sc::ErrorReport rep;
  rep.classes = CAN_ERR_CRTL;
  rep.data[1] = CAN_ERR_CRTL_TX_PASSIVE;
  const auto rec = sc::encode(rep);
  auto expected = kernel_frame(CAN_ERR_FLAG | CAN_ERR_CRTL, {0, CAN_ERR_CRTL_TX_PASSIVE, 0, 0, 0, 0, 0, 0});
  EXPECT_EQ(std::vector<std::uint8_t>(rec.begin(), rec.end()), bytes_of(expected));
  EXPECT_EQ(decode_report(expected).state(), BusState::error_passive);
}

TEST(SocketCanFrame, KernelFiltersPassWhatBusFiltersPass) {
  EXPECT_EQ(sc::to_kernel_filters({}), (std::vector<sc::KernelFilter>{{0, 0}}));
  EXPECT_EQ(sc::to_kernel_filters(std::vector<Filter>(sc::kMaxKernelFilters + 1)),
            (std::vector<sc::KernelFilter>{{0, 0}}));

  const std::vector<Filter> filters{
      Filter::parse("123:7FF").value(),       // any format, exact id
      Filter::parse("00001000:1FFFF000").value(),  // extended only
      Filter{0x080, 0x780, Filter::Format::standard},
  };
  const auto kernel = sc::to_kernel_filters(filters);
  ASSERT_EQ(kernel.size(), filters.size());
  // Emulate the kernel's comparison on the full can_id (flags included) for many frames.
  const std::array<std::uint8_t, 1> d{0};
  std::vector<Frame> frames;
  for (std::uint32_t id : {0x000u, 0x080u, 0x0FFu, 0x123u, 0x124u, 0x7FFu}) {
    frames.push_back(Frame::standard(id, d).value());
    frames.push_back(Frame::extended(id, d).value());
    frames.push_back(Frame::remote(id, IdFormat::standard, 1).value());
  }
  for (std::uint32_t id : {0x1000u, 0x1FFFu, 0x2000u, 0x1FFFF123u})
    frames.push_back(Frame::extended(id, d).value());
  for (std::size_t i = 0; i < filters.size(); ++i) {
    for (const Frame& f : frames) {
      std::uint32_t can_id = f.id();
      if (f.is_extended()) can_id |= CAN_EFF_FLAG;
      if (f.is_remote()) can_id |= CAN_RTR_FLAG;
      const bool kernel_pass = (can_id & kernel[i].mask) == (kernel[i].id & kernel[i].mask);
      EXPECT_EQ(kernel_pass, filters[i].matches(f)) << "filter " << i << " frame " << f.to_string();
    }
  }
}
