// Drives a c4g application with synthetic controller packets, without sockets: the app's on_init
// and on_cycle are called directly with a reply pre-filled like the server's safe reply.
#pragma once

#include "axon/c4g/apps/app.hpp"
#include "axon/c4g/protocol/axis_map.hpp"
#include "c4g/protocol/example_init.hpp"
#include "axon/c4g/protocol/mode.hpp"
#include "axon/c4g/protocol/transform.hpp"

#include <gtest/gtest.h>

#include <array>
#include <numbers>
#include <vector>

namespace axon::c4g::apps::test {

// One degree in radians.
inline constexpr double kDeg = std::numbers::pi / 180.0;

struct Harness {
  protocol::InitPacket init = protocol::test::manual_example_init();  // six axes on arm 1, 2 ms
  protocol::AxisMap map;
  protocol::Packet req;
  protocol::Packet rep;
  std::uint64_t cycle = 0;
  host::SwitchTracker* tracker = nullptr;  // when set: updated per cycle and handed to the app, as the Server does

  Harness() {
    req.count = 6;
    req.infpar = protocol::kDrivesOn;
  }
  void start(App& app) {
    map = protocol::AxisMap::from_init(init).value();
    app.on_init(init, map);
  }
  [[nodiscard]] protocol::ArmTransform transform() const { return protocol::ArmTransform::from_init(init, 1).value(); }
  [[nodiscard]] double period() const { return init.period_ms * 1e-3; }
  // Axis 1's motor position when axis 1 is at `link_rad` and every other axis at 0.
  [[nodiscard]] double motor_axis1(double link_rad) const {
    protocol::ArmTransform::Vector q = protocol::ArmTransform::Vector::Zero(6);
    q[0] = link_rad;
    return transform().motor_position(q)[0];
  }

  void set_modes(std::int32_t mode) {
    for (std::size_t i = 0; i < req.count; ++i) req.axes[i].mode = mode;
  }
  // The robot's actual motor positions (D3) and the controller's target (D1) at a link position [rad].
  void place_at_link(const std::array<double, 6>& q) {
    protocol::ArmTransform::Vector link(6);
    for (int i = 0; i < 6; ++i) link[i] = q[static_cast<std::size_t>(i)];
    const auto motor = transform().motor_position(link);
    for (std::size_t i = 0; i < 6; ++i) {
      req.axes[i].d3 = static_cast<float>(motor[static_cast<Eigen::Index>(i)]);
      req.axes[i].d1 = req.axes[i].d3;
    }
  }
  // One cycle: the reply starts as the server's safe reply (modes echoed, data zero; 0' echoes
  // targets; 4 holds the actual position).
  const protocol::Packet& run(App& app) {
    rep = protocol::Packet{};
    rep.num = req.num;
    rep.count = req.count;
    for (std::size_t i = 0; i < req.count; ++i) {
      rep.axes[i].mode = req.axes[i].mode;
      if (req.axes[i].mode == protocol::code(protocol::Mode::mode4)) rep.axes[i].d1 = req.axes[i].d3;
    }
    if (tracker) tracker->update(req, period());
    const host::CycleContext ctx{req, &init, &map, cycle, static_cast<std::int64_t>(cycle) * 2'000'000, tracker};
    host::ReplyBuilder builder(rep);
    app.on_cycle(ctx, builder);
    // The per-mode field table on every reply: no data in a field the axis's mode does not use.
    const auto fields = protocol::check_reply_fields(rep);
    EXPECT_TRUE(fields.ok()) << "cycle " << cycle << ": axis " << fields.axis << " mode " << fields.got << " field " << fields.field;
    ++cycle;
    req.num = (req.num + 1) & 0x7FFF;
    return rep;
  }
  [[nodiscard]] bool exit_requested() const { return protocol::exit_from_open(rep.infpar, 1); }
};

// The texts of the events the app queued.
inline std::vector<std::string> event_texts(App& app) {
  std::vector<std::string> out;
  for (const auto& e : app.drain_events()) out.push_back(app.describe(e));
  return out;
}

inline bool contains(const std::vector<std::string>& lines, std::string_view needle) {
  for (const auto& l : lines)
    if (l.find(needle) != std::string::npos) return true;
  return false;
}

// Motor-side correction (linear part) on motor axis `motor_axis` of a link-side correction of
// `link_rad` on link axis `axis` only.
inline double motor_of(const Harness& h, std::size_t axis, double link_rad, std::size_t motor_axis) {
  protocol::ArmTransform::Vector q = protocol::ArmTransform::Vector::Zero(6);
  q[static_cast<Eigen::Index>(axis)] = link_rad;
  return h.transform().motor_velocity(q)[static_cast<Eigen::Index>(motor_axis)];
}

}  // namespace axon::c4g::apps::test
