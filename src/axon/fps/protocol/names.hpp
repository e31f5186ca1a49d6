// Helpers shared by the protocol's name tables: case-insensitive name matching, and the list of
// names of the bits set in a status word (unknown bits print as BIT_<n>).
#pragma once

#include <fmt/format.h>

#include <cctype>
#include <string>
#include <string_view>
#include <vector>

namespace axon::fps::protocol {

inline bool iequals(std::string_view a, std::string_view b) noexcept {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (std::toupper(static_cast<unsigned char>(a[i])) != std::toupper(static_cast<unsigned char>(b[i]))) return false;
  }
  return true;
}

// Names of the bits set in `raw`, lowest bit first. `name_of(Bit)` names a bit in `known`.
template <class Bit, class Raw, class NameOf>
std::vector<std::string> set_bit_names(Raw raw, Raw known, NameOf name_of) {
  std::vector<std::string> out;
  for (unsigned bit = 0; bit < sizeof(Raw) * 8; ++bit) {
    const Raw m = Raw{1} << bit;
    if ((raw & m) == 0) continue;
    if ((known & m) != 0) out.emplace_back(name_of(static_cast<Bit>(bit)));
    else out.push_back(fmt::format("BIT_{}", bit));
  }
  return out;
}

}  // namespace axon::fps::protocol
