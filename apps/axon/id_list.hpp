// Robot id lists on the command line: "1-20", "3", "1,4,7-9".
#pragma once

#include "axon/core/error.hpp"

#include <fmt/format.h>

#include <charconv>
#include <cstdint>
#include <set>
#include <string>
#include <string_view>
#include <vector>

namespace axon::app {

inline Result<std::vector<std::uint16_t>> parse_id_list(std::string_view text) {
  std::set<std::uint16_t> ids;
  auto number = [](std::string_view s) -> Result<std::uint16_t> {
    unsigned v = 0;
    const auto* end = s.data() + s.size();
    auto [p, ec] = std::from_chars(s.data(), end, v);
    if (ec != std::errc() || p != end || v < 1 || v > 2047)
      return Error(CoreErrc::invalid_argument, fmt::format("robot id '{}': expected 1..2047", s));
    return static_cast<std::uint16_t>(v);
  };
  while (!text.empty()) {
    const auto comma = text.find(',');
    const std::string_view item = text.substr(0, comma);
    text = comma == std::string_view::npos ? std::string_view{} : text.substr(comma + 1);
    if (item.empty()) continue;
    const auto dash = item.find('-');
    AXON_TRY(first, number(item.substr(0, dash)));
    std::uint16_t last = first;
    if (dash != std::string_view::npos) {
      AXON_TRY(l, number(item.substr(dash + 1)));
      last = l;
    }
    if (last < first) return Error(CoreErrc::invalid_argument, fmt::format("robot id range '{}' runs backwards", item));
    for (unsigned id = first; id <= last; ++id) ids.insert(static_cast<std::uint16_t>(id));
  }
  if (ids.empty()) return Error(CoreErrc::invalid_argument, "no robot ids given");
  return std::vector<std::uint16_t>(ids.begin(), ids.end());
}

inline Result<std::vector<std::uint16_t>> parse_id_lists(const std::vector<std::string>& texts) {
  std::set<std::uint16_t> all;
  for (const auto& t : texts) {
    AXON_TRY(ids, parse_id_list(t));
    all.insert(ids.begin(), ids.end());
  }
  if (all.empty()) return Error(CoreErrc::invalid_argument, "no robot ids given");
  return std::vector<std::uint16_t>(all.begin(), all.end());
}

}  // namespace axon::app
