// Command-line checks of the c4g commands that name the problem in words ("must be > 0") instead
// of a numeric range, and refuse NaN and infinities.
#pragma once

#include <CLI/CLI.hpp>

#include <charconv>
#include <cmath>
#include <string>

namespace axon::app::c4g_cli {

// `strict`: the value must be > 0; otherwise >= 0. Every value of a list is checked.
inline CLI::Validator number_check(bool strict) {
  return CLI::Validator(
      [strict](std::string& text) -> std::string {
        double v = 0;
        const char* begin = text.data() + (text.starts_with('+') ? 1 : 0);
        const auto [end, ec] = std::from_chars(begin, text.data() + text.size(), v);
        if (ec != std::errc{} || end != text.data() + text.size() || !std::isfinite(v))
          return "'" + text + "' is not a finite number";
        if (strict ? !(v > 0) : !(v >= 0)) return "'" + text + (strict ? "' must be > 0" : "' must be >= 0");
        return {};
      },
      strict ? "> 0" : ">= 0", strict ? "POSITIVE" : "NON-NEGATIVE");
}
inline CLI::Validator positive() { return number_check(true); }
inline CLI::Validator non_negative() { return number_check(false); }

}  // namespace axon::app::c4g_cli
