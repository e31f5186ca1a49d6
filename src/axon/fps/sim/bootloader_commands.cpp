// PositionerModel: the bootloader's commands (interface document 5.2, table 4) and how it takes a
// new firmware image.
#include "axon/fps/protocol/firmware_image.hpp"
#include "axon/fps/protocol/payloads.hpp"
#include "axon/fps/sim/firmware_marker.hpp"
#include "axon/fps/sim/positioner_model.hpp"

#include <algorithm>

namespace axon::fps::sim {

namespace proto = protocol;
using proto::BootloaderBit;
using proto::CommandId;
using proto::ResponseCode;

void PositionerModel::handle_bootloader(const proto::Message& m, const proto::CommandInfo& c, Outbox& out) {
  const auto done = [&](ResponseCode code, const proto::Payload& p = {}) { reply(m, code, out, p); };
  switch (c.id) {
    case CommandId::get_id: return done(ResponseCode::accepted, proto::PositionerIdReply{config_.id}.encode());
    case CommandId::get_firmware_version:
      return done(ResponseCode::accepted, config_.bootloader.encode(config_.version_byte_order));
    case CommandId::get_status:
      return done(ResponseCode::accepted, proto::BootloaderStatusReply{boot_.status}.encode());

    case CommandId::start_firmware_upgrade: {
      auto header = proto::FirmwareUpgradeHeader::decode(m.payload.span());
      if (!header) return done(proto::response_code_for(header.error().code));
      if (header.value().size == 0 || header.value().size > config_.max_firmware_size) {
        return done(ResponseCode::value_out_of_range);
      }
      // A new announcement restarts the reception.
      boot_.receiving = true;
      boot_.size = header.value().size;
      boot_.crc32 = header.value().crc32;
      boot_.image.clear();
      boot_.image.reserve(boot_.size);
      boot_.status.set(BootloaderBit::receiving_new_firmware)
          .set(BootloaderBit::new_firmware_received, false)
          .set(BootloaderBit::new_firmware_check_ok, false)
          .set(BootloaderBit::new_firmware_check_bad, false);
      return done(ResponseCode::accepted);
    }

    case CommandId::firmware_data: {
      // Data outside an announced image: nothing to put it in.
      if (!boot_.receiving) return done(ResponseCode::value_out_of_range);
      const std::size_t remaining = boot_.size - boot_.image.size();
      if (m.payload.size() != std::min<std::size_t>(8, remaining)) return done(ResponseCode::incorrect_data_length);
      const auto bytes = m.payload.span();
      boot_.image.insert(boot_.image.end(), bytes.begin(), bytes.end());
      if (boot_.image.size() == boot_.size) {
        boot_.receiving = false;
        boot_.status.set(BootloaderBit::receiving_new_firmware, false).set(BootloaderBit::new_firmware_received);
        const std::uint32_t crc = proto::firmware_crc32(boot_.image);
        if (crc == boot_.crc32) {
          // The image becomes the main application; the one running so far stays as backup.
          const FirmwareMarker marker = read_firmware_marker(boot_.image);
          flash_.main = FirmwareSlot{marker.version.value_or(flash_.main.version), marker.bootable, crc};
          flash_.main_booted = false;
          boot_.status.set(BootloaderBit::new_firmware_check_ok).set(BootloaderBit::bsettings_changed);
          ++counters_.firmware_received;
        } else {
          boot_.status.set(BootloaderBit::new_firmware_check_bad);
          ++counters_.firmware_rejected;
        }
        boot_.image.clear();
        boot_.image.shrink_to_fit();
      }
      return done(ResponseCode::accepted);
    }

    default: break;  // application commands: refused by check_device_request already
  }
  done(ResponseCode::invalid_bootloader_command);
}

}  // namespace axon::fps::sim
