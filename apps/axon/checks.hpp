// Option validators that say what is wrong in words ("--timeout: must be > 0, got -1"), instead of
// CLI11's ranges, which print the limits of a double (309-digit numbers) for "positive".
#pragma once

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <cmath>
#include <string>

namespace axon::app {

namespace detail {
// Parses a whole number/decimal; false for text, NaN or infinity.
inline bool finite_number(const std::string& text, double& value) {
  try {
    std::size_t used = 0;
    value = std::stod(text, &used);
    return used == text.size() && std::isfinite(value);
  } catch (const std::exception&) {
    return false;
  }
}
}  // namespace detail

// value > 0
inline CLI::Validator positive() {
  return CLI::Validator(
      [](std::string& in) -> std::string {
        double v = 0;
        if (!detail::finite_number(in, v)) return fmt::format("must be a number > 0, got '{}'", in);
        return v > 0 ? std::string() : fmt::format("must be > 0, got {}", in);
      },
      "> 0", "positive");
}

// value >= 0
inline CLI::Validator non_negative() {
  return CLI::Validator(
      [](std::string& in) -> std::string {
        double v = 0;
        if (!detail::finite_number(in, v)) return fmt::format("must be a number >= 0, got '{}'", in);
        return v >= 0 ? std::string() : fmt::format("must be >= 0, got {}", in);
      },
      ">= 0", "non_negative");
}

// lo <= value <= hi
inline CLI::Validator between(double lo, double hi) {
  return CLI::Validator(
      [lo, hi](std::string& in) -> std::string {
        double v = 0;
        if (!detail::finite_number(in, v)) return fmt::format("must be a number from {:g} to {:g}, got '{}'", lo, hi, in);
        return (v >= lo && v <= hi) ? std::string() : fmt::format("must be from {:g} to {:g}, got {}", lo, hi, in);
      },
      fmt::format("{:g}..{:g}", lo, hi), "between");
}

}  // namespace axon::app
