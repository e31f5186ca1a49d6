#include "axon/c4g/protocol/error.hpp"

namespace axon::c4g::protocol {
namespace {
class ProtocolCategory final : public std::error_category {
 public:
  const char* name() const noexcept override { return "axon.c4g.protocol"; }
  std::string message(int c) const override {
    switch (static_cast<ProtocolErrc>(c)) {
      case ProtocolErrc::wrong_size:
        return "c4g datagram has the wrong size (cyclic: 12 + 36 bytes per open axis; initialization: 1200)";
      case ProtocolErrc::axis_count_mismatch:
        return "c4g cyclic packet carries another number of axes than the initialization packet announced";
      case ProtocolErrc::too_many_axes:
        return "c4g axis count out of range (1..20 open axes, at most 10 per arm)";
      case ProtocolErrc::not_finite:
        return "c4g float field is NaN or infinite";
      case ProtocolErrc::value_out_of_range:
        return "c4g integer field out of its documented range";
      case ProtocolErrc::bad_field_count:
        return "c4g initialization packet must announce 3 packet fields and 9 axis fields";
      case ProtocolErrc::bad_axis_map:
        return "c4g initialization packet's open-axis lists are inconsistent (see docs/c4g-protocol.md)";
      case ProtocolErrc::unknown_mode:
        return "c4g axis mode code is not defined by the open interface";
      case ProtocolErrc::singular_transform:
        return "c4g transmission matrix is singular (an axis has a zero transmission ratio)";
      case ProtocolErrc::field_not_null:
        return "c4g reply carries data in a field its axis mode does not use (the manual wants it null)";
    }
    return "unknown c4g protocol error";
  }
};
}  // namespace

const std::error_category& protocol_category() noexcept {
  static const ProtocolCategory c;
  return c;
}

}  // namespace axon::c4g::protocol
