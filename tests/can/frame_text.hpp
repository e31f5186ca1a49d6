// A CAN frame from its cansend notation ("123#DEADBEEF"), for tests: a bad string fails loudly.
#pragma once

#include "axon/can/frame.hpp"

namespace axon::can::test {

inline Frame F(const char* text) { return Frame::parse(text).value(); }

}  // namespace axon::can::test
