// The initialization packet printed in the manual's example (a six-axis arm, 2 ms period, software
// 3.11.115): shared by the init-packet, axis-map and transform tests.
#pragma once

#include "c4g/protocol/init_packet.hpp"

namespace axon::c4g::protocol::test {

inline InitPacket manual_example_init() {
  InitPacket p;
  p.protocol_number = 10;
  p.fields_per_packet = 3;
  p.fields_per_axis = 9;
  p.open_axes = 6;
  // Start-up modes: all 0. Open axes of arm 1: logical 1..6; the printout's "X" slots are 0 here.
  p.open_axis_list[0] = {1, 2, 3, 4, 5, 6, 0, 0, 0, 0};
  p.calibration[0] = {0.142965f, 0.170353f, 0.222660f, 0.405883f, 0.039380f, 0.355824f, 0, 0, 0, 0};
  p.current_limit[0] = {24.5f, 24.5f, 24.5f, 9.5f, 9.5f, 9.5f, 0, 0, 0, 0};
  p.transmission_ratio[0] = {-181.587296f, 159.260864f, 162.473694f, 72.585968f, 78.75f, -50.0f, 0, 0, 0, 0};
  p.influence[0] = {0, 0, 0, -0.02f, 0.0204f, 0.02f, 0, 0, 0, 0};
  p.following_error[0] = {7.5f, 7.5f, 7.5f, 7.5f, 7.5f, 0, 0, 0, 0, 0};
  p.packet_field_types = {1, 2, 3};
  p.axis_field_types = {1, 2, 2, 2, 2, 2, 3, 3, 3};
  p.period_ms = 2;
  p.version_major = 3;
  p.version_minor = 11;
  p.version_build = 115;
  return p;
}

}  // namespace axon::c4g::protocol::test
