// The shape of a payload as the command table declares it: which fields, in which order, how wide,
// in which unit. Fields are packed without gaps from byte 0, little-endian. A layout also gives the
// accepted size range (all fixed except firmware data, which is 1..8 bytes).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>

namespace axon::fps::protocol {

enum class FieldType : std::uint8_t { u32, i32, u64, bytes };

enum class Unit : std::uint8_t {
  none,                 // a plain number: count, index, id, raw sensor reading
  position,             // int32, 2^30 steps per turn of the arm (units.hpp)
  time,                 // uint32, 0.5 ms steps
  motor_rpm,            // uint32, revolutions per minute at the motor, before the gearbox
  percent,              // current or torque in percent of the motor's rating
  degrees,              // int32, whole degrees
  collision_margin,     // int32, -30..30
  firmware_version,     // uint32 0x00XXYYZZ (firmware_version.hpp)
  status,               // uint64 status word of the main application (status.hpp)
  bootloader_status,    // uint32 status word of the bootloader (bootloader_status.hpp)
  crc32,                // zlib CRC-32 of a firmware image
  raw_bytes,            // opaque bytes (a slice of a firmware image)
};

struct Field {
  std::string_view name;
  FieldType type = FieldType::u32;
  Unit unit = Unit::none;
};

constexpr std::size_t field_width(FieldType t) noexcept {
  switch (t) {
    case FieldType::u32:
    case FieldType::i32: return 4;
    case FieldType::u64: return 8;
    case FieldType::bytes: return 0;  // variable
  }
  return 0;
}

struct Layout {
  std::uint8_t min_size = 0;
  std::uint8_t max_size = 0;
  std::uint8_t field_count = 0;
  std::array<Field, 2> fields{};

  [[nodiscard]] constexpr bool accepts(std::size_t n) const noexcept { return n >= min_size && n <= max_size; }
  [[nodiscard]] constexpr bool is_empty() const noexcept { return max_size == 0; }
  [[nodiscard]] constexpr bool is_fixed() const noexcept { return min_size == max_size; }
};

namespace layout {
inline constexpr Layout none{};
constexpr Layout one(Field f) noexcept {
  const auto w = static_cast<std::uint8_t>(field_width(f.type));
  return Layout{w, w, 1, {f, Field{}}};
}
constexpr Layout two(Field a, Field b) noexcept {
  const auto w = static_cast<std::uint8_t>(field_width(a.type) + field_width(b.type));
  return Layout{w, w, 2, {a, b}};
}
constexpr Layout bytes(std::string_view name, std::uint8_t min, std::uint8_t max) noexcept {
  return Layout{min, max, 1, {Field{name, FieldType::bytes, Unit::raw_bytes}, Field{}}};
}
}  // namespace layout

}  // namespace axon::fps::protocol
