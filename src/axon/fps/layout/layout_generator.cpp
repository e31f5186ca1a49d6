#include "axon/fps/layout/layout_generator.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace axon::fps {
namespace {

// A grid site in axial coordinates: position = q * (pitch, 0) + r * (pitch / 2, pitch * sqrt(3) / 2).
struct Axial {
  int q = 0;
  int r = 0;
};

// Rotation by 60 degrees counter-clockwise about the centre site.
Axial rotate60(Axial a) { return Axial{-a.r, a.q + a.r}; }

double x_of(Axial a, double pitch) { return pitch * (a.q + a.r / 2.0); }
double y_of(Axial a, double pitch) { return pitch * a.r * std::sqrt(3.0) / 2.0; }

// Sizes of `parts` nearly equal chunks of n, larger first (84 -> 21 21 21 21, 83 -> 21 21 21 20).
std::vector<int> chunks(int n, int parts) {
  std::vector<int> out;
  for (int i = 0; i < parts; ++i) out.push_back(n / parts + (i < n % parts ? 1 : 0));
  return out;
}

}  // namespace

Result<FocalPlane> generate_layout(const LayoutGeneratorOptions& o) {
  if (o.robots < kSextants || o.robots > 2000)
    return Error(CoreErrc::invalid_argument, fmt::format("layout generator: {} robots; expected 6..2000", o.robots));
  if (o.buses_per_sextant < 1 || o.buses_per_sextant > kMaxGatewayChannels)
    return Error(CoreErrc::invalid_argument, "layout generator: 1..4 buses per sextant");
  if (o.fiducials_per_sextant < 0 || o.apogee_per_sextant < 0 || !(o.pitch_mm > 0))
    return Error(CoreErrc::invalid_argument, "layout generator: negative counts or pitch");

  // Robots per sextant: the remainder spread evenly over the sextants.
  const int extra = o.robots % kSextants;
  std::vector<int> per_sextant;
  for (int k = 0; k < kSextants; ++k)
    per_sextant.push_back(o.robots / kSextants + ((k + 1) * extra / kSextants > k * extra / kSextants ? 1 : 0));
  const int most = *std::max_element(per_sextant.begin(), per_sextant.end());
  const int fewest = *std::min_element(per_sextant.begin(), per_sextant.end());
  if (o.apogee_per_sextant > fewest)
    return Error(CoreErrc::invalid_argument, "layout generator: more apogee fibres than robots in a sextant");
  const int sites = most + o.fiducials_per_sextant;

  // The sites of the first wedge (0 <= angle < 60 deg: q > 0, r >= 0), innermost first.
  std::vector<Axial> wedge;
  const int span = static_cast<int>(std::ceil(std::sqrt(2.0 * sites))) + 2;
  for (int q = 1; q <= span; ++q)
    for (int r = 0; r <= span; ++r) wedge.push_back(Axial{q, r});
  auto radius2 = [](Axial a) { return a.q * a.q + a.q * a.r + a.r * a.r; };
  std::sort(wedge.begin(), wedge.end(), [&](Axial a, Axial b) {
    if (radius2(a) != radius2(b)) return radius2(a) < radius2(b);
    return std::atan2(y_of(a, 1), x_of(a, 1)) < std::atan2(y_of(b, 1), x_of(b, 1));
  });
  wedge.resize(static_cast<std::size_t>(sites));

  // Fiducial slots in the wedge, spread over the radii (never the innermost site: it touches the
  // centre fiducial).
  std::vector<bool> is_fiducial(wedge.size(), false);
  for (int j = 0; j < o.fiducials_per_sextant; ++j) {
    const auto slot = static_cast<std::size_t>((j + 1) * (fewest + o.fiducials_per_sextant) / (o.fiducials_per_sextant + 1));
    is_fiducial[std::min(slot, wedge.size() - 1)] = true;
  }

  FocalPlaneSpec spec;
  spec.name = o.name;
  spec.pitch_mm = o.pitch_mm;
  spec.neighbours.robot_radius_mm = 2 * o.pitch_mm + 3.46;
  spec.neighbours.adjacent_radius_mm = 1.1 * o.pitch_mm;
  spec.fiducials.push_back(Fiducial{1, 0.0, 0.0});
  std::uint16_t next_id = 1;
  for (int k = 0; k < kSextants; ++k) {
    const int sextant = k + 1;
    spec.gateways.push_back(GatewaySite{static_cast<std::uint16_t>(sextant), fmt::format(fmt::runtime(o.gateway_address), sextant),
                                        sextant, o.buses_per_sextant});
    std::vector<Axial> robots;
    for (std::size_t i = 0; i < wedge.size(); ++i) {
      Axial a = wedge[i];
      for (int t = 0; t < k; ++t) a = rotate60(a);
      if (is_fiducial[i]) {
        spec.fiducials.push_back(Fiducial{static_cast<int>(spec.fiducials.size()) + 1, x_of(a, o.pitch_mm), y_of(a, o.pitch_mm)});
      } else if (static_cast<int>(robots.size()) < per_sextant[static_cast<std::size_t>(k)]) {
        robots.push_back(a);
      }
    }
    // Chains by azimuth within the sextant (relative to the wedge's start), each from the centre out.
    const double start = k * std::numbers::pi / 3;
    auto azimuth = [&](Axial a) {
      double t = std::atan2(y_of(a, 1), x_of(a, 1)) - start;
      while (t < -1e-9) t += 2 * std::numbers::pi;
      return t;
    };
    std::stable_sort(robots.begin(), robots.end(), [&](Axial a, Axial b) { return azimuth(a) < azimuth(b); });
    const auto sizes = chunks(static_cast<int>(robots.size()), o.buses_per_sextant);
    std::size_t at = 0;
    int in_sextant = 0;
    for (int b = 0; b < o.buses_per_sextant; ++b) {
      std::vector<Axial> chain(robots.begin() + static_cast<std::ptrdiff_t>(at),
                               robots.begin() + static_cast<std::ptrdiff_t>(at + static_cast<std::size_t>(sizes[static_cast<std::size_t>(b)])));
      at += static_cast<std::size_t>(sizes[static_cast<std::size_t>(b)]);
      std::stable_sort(chain.begin(), chain.end(), [&](Axial a, Axial c) { return radius2(a) < radius2(c); });
      for (const Axial& a : chain) {
        RobotSite r;
        r.id = next_id++;
        r.x_mm = x_of(a, o.pitch_mm);
        r.y_mm = y_of(a, o.pitch_mm);
        r.sextant = sextant;
        r.bus = BusRef{static_cast<std::uint16_t>(sextant), static_cast<std::uint8_t>(b + 1)};
        r.fibres = {Fibre::metrology, Fibre::boss};
        const int n = per_sextant[static_cast<std::size_t>(k)];
        if ((in_sextant + 1) * o.apogee_per_sextant / n > in_sextant * o.apogee_per_sextant / n)
          r.fibres.push_back(Fibre::apogee);
        ++in_sextant;
        spec.robots.push_back(std::move(r));
      }
    }
  }
  return FocalPlane::build(std::move(spec));
}

}  // namespace axon::fps
