#include "axon/fps/layout/layout_check.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>

namespace axon::fps {
namespace {

std::string buses_text(const std::vector<BusRef>& buses) {
  std::string s;
  for (const auto& b : buses) s += fmt::format("{}{}", s.empty() ? "" : " ", b.to_string());
  return s;
}

}  // namespace

LayoutCheck check_layout(const FocalPlane& plane, const BusSweep& sweep) {
  LayoutCheck out;
  out.failed_buses = sweep.failed;
  std::map<std::uint16_t, std::vector<BusRef>> answered;
  for (const auto& [bus, ids] : sweep.found)
    for (auto id : ids) answered[id].push_back(bus);

  for (const auto& r : plane.robots()) {
    const bool swept = sweep.found.count(r.bus) != 0;
    auto it = answered.find(r.id);
    if (it == answered.end()) {
      if (!swept) out.not_checked.push_back(r.id);
      else if (r.offline) out.offline_silent.push_back(r.id);
      else out.missing.push_back(r.id);
      continue;
    }
    const auto& where = it->second;
    if (r.offline) out.offline_answered.push_back(r.id);
    if (where.size() > 1) {
      out.duplicated.push_back(Misplaced{r.id, where});
    } else if (where.front() != r.bus) {
      out.wrong_bus.push_back(WrongBus{r.id, r.bus, where});
    } else {
      out.matched.push_back(r.id);
    }
  }
  for (const auto& [id, where] : answered) {
    if (plane.find(id)) continue;
    out.unexpected.push_back(Misplaced{id, where});
    if (where.size() > 1) out.duplicated.push_back(Misplaced{id, where});
  }
  for (auto* v : {&out.matched, &out.missing, &out.offline_answered, &out.offline_silent, &out.not_checked})
    std::sort(v->begin(), v->end());
  std::sort(out.duplicated.begin(), out.duplicated.end(), [](const Misplaced& a, const Misplaced& b) { return a.id < b.id; });
  return out;
}

std::string LayoutCheck::to_text() const {
  std::string s;
  for (auto id : missing) s += fmt::format("missing      robot {} did not answer on its bus\n", id);
  for (const auto& w : wrong_bus)
    s += fmt::format("wrong bus    robot {} answered on {} (layout: {})\n", w.id, buses_text(w.found), w.expected.to_string());
  for (const auto& u : unexpected)
    s += fmt::format("unexpected   robot {} answered on {} but is not in the layout\n", u.id, buses_text(u.found));
  for (const auto& d : duplicated)
    s += fmt::format("duplicated   robot {} answered on several buses: {}\n", d.id, buses_text(d.found));
  for (auto id : offline_answered) s += fmt::format("note         robot {} is marked offline but answered\n", id);
  for (const auto& [bus, why] : failed_buses) s += fmt::format("bus failed   {}: {}\n", bus.to_string(), why);
  if (!not_checked.empty()) s += fmt::format("not checked  {} robots on buses not swept\n", not_checked.size());
  s += fmt::format("{}: {} matched, {} missing, {} on the wrong bus, {} unexpected, {} duplicated, {} offline as marked\n",
                   ok() ? "OK" : "MISMATCH", matched.size(), missing.size(), wrong_bus.size(), unexpected.size(),
                   duplicated.size(), offline_silent.size());
  return s;
}

}  // namespace axon::fps
