// Errors of the c4g protocol codecs: what is wrong with a datagram, a field value or an
// initialization packet that arrived from the robot controller or that the PC wants to send.
#pragma once

#include "axon/core/error.hpp"

namespace axon::c4g::protocol {

enum class ProtocolErrc {
  wrong_size = 1,       // datagram (or output buffer) size is not what the layout needs
  axis_count_mismatch,  // a cyclic packet with another number of axes than the initialization packet
  too_many_axes,        // an axis count outside 1..20 (or an arm with more than 10 axes)
  not_finite,           // a float field holding NaN or an infinity
  value_out_of_range,   // an integer field outside its documented range (protocol number, period...)
  bad_field_count,      // initialization packet announcing other than 3 packet / 9 axis fields
  bad_axis_map,         // open-axis lists that do not describe a consistent axis mapping
  unknown_mode,         // an axis mode code the interface does not define
  singular_transform,   // transmission matrix that cannot be inverted (a zero transmission ratio)
  field_not_null,       // a reply field the axis's mode does not use is not zero
};

const std::error_category& protocol_category() noexcept;
inline std::error_code make_error_code(ProtocolErrc e) noexcept {
  return {static_cast<int>(e), protocol_category()};
}

}  // namespace axon::c4g::protocol

template <>
struct std::is_error_code_enum<axon::c4g::protocol::ProtocolErrc> : std::true_type {};
