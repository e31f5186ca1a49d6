// The initialization packet printed in the manual's example (a six-axis arm, 2 ms period, software
// 3.11.115): shared by the init-packet, axis-map and transform tests. The constants live with the
// simulator's robots (c4g/sim/robots.cpp), which announces exactly this packet.
#pragma once

#include "axon/c4g/protocol/init_packet.hpp"
#include "axon/c4g/sim/robots.hpp"

namespace axon::c4g::protocol::test {

inline InitPacket manual_example_init() { return sim::six_axis_init(); }

}  // namespace axon::c4g::protocol::test
