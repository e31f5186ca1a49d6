#include "axon/fps/plc/register_map.hpp"

#include "axon/fps/plc/error.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

namespace axon::fps::plc {

std::string_view relay_kind_name(RelayKind k) noexcept {
  switch (k) {
    case RelayKind::positioner_power: return "positioner power";
    case RelayKind::gateway_power: return "gateway power";
    case RelayKind::sync_line: return "sync line";
  }
  return "?";
}

std::string Relay::to_string() const {
  if (kind == RelayKind::sync_line) return std::string(relay_kind_name(kind));
  return fmt::format("{} {}", relay_kind_name(kind), sextant);
}

std::optional<double> AnalogInput::decode(std::uint16_t raw) const noexcept {
  if (is_signed) {
    if (raw == 0x8000) return std::nullopt;
    return static_cast<std::int16_t>(raw) * scale;
  }
  if (raw == 0xFFFF) return std::nullopt;
  return raw * scale;
}

std::uint16_t AnalogInput::encode(std::optional<double> value) const noexcept {
  if (!value || !std::isfinite(*value)) return is_signed ? 0x8000 : 0xFFFF;
  const double counts = std::round(*value / scale);
  if (is_signed) {
    const double c = std::clamp(counts, -32767.0, 32767.0);
    return static_cast<std::uint16_t>(static_cast<std::int16_t>(c));
  }
  return static_cast<std::uint16_t>(std::clamp(counts, 0.0, 65534.0));
}

std::vector<AnalogInput> RegisterMap::default_temperatures() {
  std::vector<AnalogInput> t;
  std::uint16_t a = 0;
  for (const char* name : {"fps_plate_centre", "fps_plate_edge", "ieb_air", "ieb_power_supplies", "coolant_supply",
                           "coolant_return"})
    t.push_back(AnalogInput{name, a++, 0.1, true, "degC"});
  return t;
}

namespace {

Result<void> load_coils(const core::ConfigNode& node, const char* key, std::array<std::uint16_t, kSextants>& out) {
  if (!node.has(key)) return ok();
  AXON_TRY(list, node.child(key));
  AXON_TRY(items, list.items());
  if (items.size() != kSextants) return list.error(CoreErrc::config_bad_value, "expected 6 coil addresses, one per sextant");
  for (std::size_t i = 0; i < items.size(); ++i) {
    AXON_TRY(v, items[i].as<std::uint16_t>());
    out[i] = v;
  }
  return ok();
}

Result<void> load_input(const core::ConfigNode& node, AnalogInput& in, bool need_name) {
  if (!node.is_map()) return node.error(CoreErrc::config_bad_value, "expected {address: N, scale: X}");
  AXON_TRY(node.reject_unknown({"name", "address", "scale", "signed", "unit"}));
  if (need_name) {
    AXON_TRY(name, node.get<std::string>("name"));
    in.name = name;
  }
  AXON_TRY(address, node.get<std::uint16_t>("address"));
  in.address = address;
  AXON_TRY(scale, node.get_or<double>("scale", in.scale));
  if (!(scale > 0)) return node.error(CoreErrc::config_bad_value, "scale must be positive");
  in.scale = scale;
  AXON_TRY(is_signed, node.get_or<bool>("signed", in.is_signed));
  in.is_signed = is_signed;
  AXON_TRY(unit, node.get_or<std::string>("unit", in.unit));
  in.unit = unit;
  return ok();
}

}  // namespace

Result<RegisterMap> RegisterMap::from_config(const core::ConfigNode& node) {
  RegisterMap m;
  if (!node.is_map()) return node.error(CoreErrc::config_bad_value, "expected a register map");
  AXON_TRY(node.reject_unknown({"unit_id", "coils", "input_registers"}));
  if (node.has("unit_id")) {
    AXON_TRY(u, node.get_in<int>("unit_id", 0, 255));
    m.unit_id = u;
  }
  if (node.has("coils")) {
    AXON_TRY(c, node.child("coils"));
    AXON_TRY(c.reject_unknown({"positioner_power", "gateway_power", "sync_line"}));
    AXON_TRY(load_coils(c, "positioner_power", m.positioner_power));
    AXON_TRY(load_coils(c, "gateway_power", m.gateway_power));
    if (c.has("sync_line")) {
      AXON_TRY(s, c.get<std::uint16_t>("sync_line"));
      m.sync_line = s;
    }
  }
  if (node.has("input_registers")) {
    AXON_TRY(r, node.child("input_registers"));
    AXON_TRY(r.reject_unknown({"temperatures", "humidity", "pressure", "coolant_flow"}));
    if (r.has("temperatures")) {
      AXON_TRY(list, r.child("temperatures"));
      AXON_TRY(items, list.items());
      m.temperatures.clear();
      for (const auto& item : items) {
        AnalogInput in{"", 0, 0.1, true, "degC"};
        AXON_TRY(load_input(item, in, true));
        m.temperatures.push_back(in);
      }
    }
    for (auto [key, in] : {std::pair<const char*, AnalogInput*>{"humidity", &m.humidity},
                           {"pressure", &m.pressure},
                           {"coolant_flow", &m.coolant_flow}}) {
      if (!r.has(key)) continue;
      AXON_TRY(c, r.child(key));
      AXON_TRY(load_input(c, *in, false));
    }
  }
  if (auto v = m.validate(); !v) return node.error(CoreErrc::config_bad_value, v.error().detail);
  return m;
}

Result<void> RegisterMap::validate() const {
  std::map<std::uint16_t, std::string> coils;
  for (const auto& r : relays()) {
    const auto a = coil_of(r);
    if (auto [it, fresh] = coils.emplace(a, r.to_string()); !fresh)
      return Error(PlcErrc::bad_map, fmt::format("coil {} is used by both {} and {}", a, it->second, r.to_string()));
  }
  std::map<std::uint16_t, std::string> regs;
  std::set<std::string> names;
  for (const auto* in : inputs()) {
    if (in->name.empty()) return Error(PlcErrc::bad_map, "an input register without a name");
    if (!names.insert(in->name).second) return Error(PlcErrc::bad_map, fmt::format("two inputs named '{}'", in->name));
    if (auto [it, fresh] = regs.emplace(in->address, in->name); !fresh)
      return Error(PlcErrc::bad_map,
                   fmt::format("input register {} is used by both {} and {}", in->address, it->second, in->name));
    if (!(in->scale > 0)) return Error(PlcErrc::bad_map, fmt::format("input '{}': scale must be positive", in->name));
  }
  if (unit_id < 0 || unit_id > 255) return Error(PlcErrc::bad_map, "unit id must be 0..255");
  return ok();
}

std::uint16_t RegisterMap::coil_of(Relay r) const noexcept {
  const auto i = static_cast<std::size_t>(std::clamp(r.sextant, 1, kSextants) - 1);
  switch (r.kind) {
    case RelayKind::positioner_power: return positioner_power[i];
    case RelayKind::gateway_power: return gateway_power[i];
    case RelayKind::sync_line: return sync_line;
  }
  return sync_line;
}

std::optional<Relay> RegisterMap::relay_at(std::uint16_t coil) const noexcept {
  for (int s = 1; s <= kSextants; ++s) {
    if (positioner_power[static_cast<std::size_t>(s - 1)] == coil) return Relay{RelayKind::positioner_power, s};
    if (gateway_power[static_cast<std::size_t>(s - 1)] == coil) return Relay{RelayKind::gateway_power, s};
  }
  if (coil == sync_line) return Relay{RelayKind::sync_line, 0};
  return std::nullopt;
}

std::vector<Relay> RegisterMap::relays() const {
  std::vector<Relay> out;
  for (int s = 1; s <= kSextants; ++s) out.push_back(Relay{RelayKind::positioner_power, s});
  for (int s = 1; s <= kSextants; ++s) out.push_back(Relay{RelayKind::gateway_power, s});
  out.push_back(Relay{RelayKind::sync_line, 0});
  return out;
}

std::uint16_t RegisterMap::coil_span() const noexcept {
  std::uint16_t hi = 0;
  for (const auto& r : relays()) hi = std::max<std::uint16_t>(hi, static_cast<std::uint16_t>(coil_of(r) + 1));
  return hi;
}

std::uint16_t RegisterMap::input_register_span() const noexcept {
  std::uint16_t hi = 0;
  for (const auto* in : inputs()) hi = std::max<std::uint16_t>(hi, static_cast<std::uint16_t>(in->address + 1));
  return hi;
}

std::vector<const AnalogInput*> RegisterMap::inputs() const {
  std::vector<const AnalogInput*> out;
  for (const auto& t : temperatures) out.push_back(&t);
  out.push_back(&humidity);
  out.push_back(&pressure);
  out.push_back(&coolant_flow);
  return out;
}

const AnalogInput* RegisterMap::input(std::string_view name) const noexcept {
  for (const auto* in : inputs())
    if (in->name == name) return in;
  return nullptr;
}

}  // namespace axon::fps::plc
