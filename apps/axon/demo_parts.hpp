// The parts of `axon demo` after CAN and fps, one file each: every family against its simulator.
#pragma once

namespace axon::app {

// c4g: a robot program on the controller simulator against the PC server (demo_c4g.cpp). Exit code.
int demo_c4g();

}  // namespace axon::app
