// The focal plane as built: where every robot sits and which way it faces, which sextant powers it,
// which gateway channel (bus) it talks on, which fibres it carries, its arms where metrology
// measured them; the plane's nominal arm lengths; where the fiducials and the guide cameras are;
// who is whose neighbour.
//
// A FocalPlane is built once (from a layout file, layout_file.hpp, or the generator,
// layout_generator.hpp) and is immutable afterwards; construction validates it and precomputes
// the neighbour lists, so lookups during planning and collision checks cost nothing.
//
// Conventions: positions in mm in the focal-plane frame (x right, y up, origin at the centre);
// sextants 1..6; gateways are numbered by the layout (1..6 on the telescope), their buses are the
// CAN@net channels 1..4.
#pragma once

#include "axon/core/error.hpp"
#include "axon/fps/layout/arm_lengths.hpp"

#include <compare>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace axon::fps {

inline constexpr double kDefaultPitchMm = 22.4;
inline constexpr int kSextants = 6;
inline constexpr int kMaxGatewayChannels = 4;  // CAN@net NT 420
// A guide camera's edge shorter than this is taken for a typo (two equal end points).
inline constexpr double kMinGuideCameraLengthMm = 1e-6;

// One CAN bus of the focal plane: a gateway and one of its channels.
struct BusRef {
  std::uint16_t gateway = 0;  // layout's gateway id
  std::uint8_t channel = 0;   // 1..4
  auto operator<=>(const BusRef&) const = default;
  [[nodiscard]] std::string to_string() const;  // "gw2/3"
};

enum class Fibre : std::uint8_t { boss, apogee, metrology };
[[nodiscard]] std::string_view fibre_name(Fibre f) noexcept;
[[nodiscard]] std::optional<Fibre> parse_fibre(std::string_view name) noexcept;

// Per-robot corrections of the arms' zero points, in degrees (from metrology).
struct ArmOffsets {
  double alpha_deg = 0;
  double beta_deg = 0;
  bool operator==(const ArmOffsets&) const = default;
};

// A fibre's position on the beta arm as metrology measured it, in the beta-arm frame (x along the
// arm from the beta axis, y across it towards increasing beta), mm.
struct FibreOffset {
  Fibre fibre = Fibre::boss;
  double x_mm = 0;
  double y_mm = 0;
  bool operator==(const FibreOffset&) const = default;
};

struct RobotSite {
  std::uint16_t id = 0;  // positioner id on the bus, 1..2047
  double x_mm = 0;
  double y_mm = 0;
  // Direction of the robot's own x axis (alpha = 0), counter-clockwise from the plane's x axis.
  double orientation_deg = 0;
  // This robot's arms where metrology measured them (nullopt: the layout's ArmLengths).
  std::optional<double> alpha_length_mm;  // alpha axis to beta axis
  std::optional<double> beta_length_mm;   // beta axis to the arm's end; shifts fibres and the
                                          // collision segment by the difference to beta_tip_mm
  std::vector<FibreOffset> fibre_offsets; // measured fibre positions (empty: the arm design's)
  int sextant = 0;  // 1..6
  BusRef bus;
  std::vector<Fibre> fibres;
  bool disabled = false;  // answers but must not be moved (e.g. a broken arm, folded for good)
  bool offline = false;   // not expected to answer at all (unpowered, removed, dead)
  std::optional<ArmOffsets> offsets;

  [[nodiscard]] bool carries(Fibre f) const noexcept;
};

struct Fiducial {
  int id = 0;
  double x_mm = 0;
  double y_mm = 0;
};

// A guide camera's edge as the robots see it: a fixed segment obstacle with its own buffer (the
// beta arm's capsule must stay farther than its buffer + this one from the segment).
struct GuideCamera {
  int id = 0;
  double x1_mm = 0, y1_mm = 0;
  double x2_mm = 0, y2_mm = 0;
  double buffer_mm = 3.0;
  bool operator==(const GuideCamera&) const = default;
};

struct GatewaySite {
  std::uint16_t id = 0;
  std::string address;  // HOST:PORT of its CAN@net ASCII server
  int sextant = 0;      // the sextant it serves (0: not tied to one, e.g. on a bench)
  int channels = kMaxGatewayChannels;
};

struct NeighbourOptions {
  // Robots whose centres are within this distance can touch each other's arms (two pitches plus a
  // margin, as the planner in service uses): 18 for an interior robot of the telescope's grid.
  double robot_radius_mm = 48.26;
  // The robots right next to one (one pitch plus tolerance): 6 for an interior robot.
  double adjacent_radius_mm = kDefaultPitchMm * 1.1;
  // Fiducials a robot's beta arm can reach: arm reach (ArmLengths: alpha arm + beta tip) plus both
  // collision buffers.
  double fiducial_radius_mm = 30.0;
};

struct Neighbours {
  std::vector<std::uint16_t> robots;    // within robot_radius_mm, nearest first
  std::vector<std::uint16_t> adjacent;  // within adjacent_radius_mm, nearest first
  std::vector<int> fiducials;           // within fiducial_radius_mm, nearest first
};

struct FocalPlaneSpec {
  std::string name;
  double pitch_mm = kDefaultPitchMm;
  NeighbourOptions neighbours;
  std::vector<GatewaySite> gateways;
  ArmLengths arms;  // every robot's nominal arms (a robot's own lengths override them)
  std::vector<RobotSite> robots;
  std::vector<Fiducial> fiducials;
  std::vector<GuideCamera> guide_cameras;
};

class FocalPlane {
 public:
  // Validates (ids unique, positions distinct and finite, sextants 1..6, every robot on a declared
  // gateway's channel; arm lengths finite and positive; guide cameras finite, of non-zero length,
  // with a non-negative buffer and unique ids) and precomputes the neighbour lists. Errors: CoreErrc::config_bad_value with the
  // offending robot named. The file loader validates first with file:line:col locations; this is
  // the last line of defence for layouts built in code.
  static Result<FocalPlane> build(FocalPlaneSpec spec);

  [[nodiscard]] const std::string& name() const noexcept { return spec_.name; }
  [[nodiscard]] double pitch_mm() const noexcept { return spec_.pitch_mm; }
  [[nodiscard]] const NeighbourOptions& neighbour_options() const noexcept { return spec_.neighbours; }
  [[nodiscard]] const std::vector<RobotSite>& robots() const noexcept { return spec_.robots; }
  [[nodiscard]] const std::vector<Fiducial>& fiducials() const noexcept { return spec_.fiducials; }
  [[nodiscard]] const std::vector<GatewaySite>& gateways() const noexcept { return spec_.gateways; }
  [[nodiscard]] const ArmLengths& arms() const noexcept { return spec_.arms; }
  [[nodiscard]] const std::vector<GuideCamera>& guide_cameras() const noexcept { return spec_.guide_cameras; }
  [[nodiscard]] const FocalPlaneSpec& spec() const noexcept { return spec_; }

  // nullptr when the id is not in the layout.
  [[nodiscard]] const RobotSite* find(std::uint16_t id) const noexcept;
  [[nodiscard]] const GatewaySite* gateway(std::uint16_t id) const noexcept;
  [[nodiscard]] const Fiducial* fiducial(int id) const noexcept;
  // Empty lists for an unknown id.
  [[nodiscard]] const Neighbours& neighbours(std::uint16_t id) const noexcept;

  // Robot ids by bus, sextant, gateway (ascending ids).
  [[nodiscard]] std::map<BusRef, std::vector<std::uint16_t>> by_bus() const;
  [[nodiscard]] std::map<int, std::vector<std::uint16_t>> by_sextant() const;
  [[nodiscard]] std::map<std::uint16_t, std::vector<std::uint16_t>> by_gateway() const;
  // Every bus the layout uses.
  [[nodiscard]] std::vector<BusRef> buses() const;

 private:
  explicit FocalPlane(FocalPlaneSpec spec) : spec_(std::move(spec)) {}
  void compute_neighbours();

  FocalPlaneSpec spec_;
  std::map<std::uint16_t, std::size_t> index_;
  std::vector<Neighbours> neighbours_;  // parallel to spec_.robots
};

}  // namespace axon::fps
