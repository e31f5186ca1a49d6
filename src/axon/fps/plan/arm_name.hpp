// The two arms of a robot as the planner, the host, the reports and the command lines name them:
// 'a' (alpha) and 'b' (beta) in code, "alpha" and "beta" in words.
#pragma once

#include <optional>
#include <string_view>

namespace axon::fps {

// "alpha", "beta"; "" for anything else (an arm not chosen).
constexpr std::string_view arm_name(char arm) noexcept { return arm == 'a' ? "alpha" : arm == 'b' ? "beta" : ""; }

// 'a' for "alpha", 'b' for "beta"; nothing for any other word.
constexpr std::optional<char> arm_from_name(std::string_view name) noexcept {
  if (name == "alpha") return 'a';
  if (name == "beta") return 'b';
  return std::nullopt;
}

}  // namespace axon::fps
