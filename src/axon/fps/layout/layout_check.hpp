// Checking the focal plane against what answered on the buses.
//
// The input is the result of a broadcast GET_ID sweep: for every bus swept, the ids that answered
// (and the buses whose sweep failed). The check is a pure function, so the same rules serve the CLI,
// start-up checks and tests:
//   - missing: in the layout on a swept bus, not offline, answered nowhere;
//   - wrong_bus: in the layout, answered only on buses other than its own;
//   - unexpected: answered, but not in the layout at all;
//   - duplicated: answered on more than one bus (two robots share an id, or buses are bridged);
//   - offline_answered: marked offline but answered (informational: update the layout);
//   - not_checked: in the layout on a bus that was not swept or whose sweep failed.
// ok() is true when there is nothing missing, misplaced, unexpected or duplicated.
#pragma once

#include "axon/core/error.hpp"
#include "axon/fps/layout/focal_plane.hpp"

#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace axon::fps {

struct BusSweep {
  std::map<BusRef, std::set<std::uint16_t>> found;  // every bus swept successfully, even if empty
  std::map<BusRef, std::string> failed;             // buses whose sweep failed, and why
};

struct WrongBus {
  std::uint16_t id = 0;
  BusRef expected;
  std::vector<BusRef> found;
};

struct Misplaced {
  std::uint16_t id = 0;
  std::vector<BusRef> found;
};

struct LayoutCheck {
  std::vector<std::uint16_t> matched;           // answered on their own bus only
  std::vector<std::uint16_t> missing;
  std::vector<WrongBus> wrong_bus;
  std::vector<Misplaced> unexpected;
  std::vector<Misplaced> duplicated;
  std::vector<std::uint16_t> offline_answered;
  std::vector<std::uint16_t> offline_silent;    // offline and silent, as expected
  std::vector<std::uint16_t> not_checked;
  std::map<BusRef, std::string> failed_buses;

  [[nodiscard]] bool ok() const noexcept {
    return missing.empty() && wrong_bus.empty() && unexpected.empty() && duplicated.empty();
  }
  // One line per finding, and a summary line.
  [[nodiscard]] std::string to_text() const;
};

[[nodiscard]] LayoutCheck check_layout(const FocalPlane& plane, const BusSweep& sweep);

}  // namespace axon::fps
