#include "axon/fps/plan/layout_model.hpp"

#include <fmt/format.h>

namespace axon::fps::plan {

ArmDesign design_of(const FocalPlane& plane, const LayoutModelOptions& o) {
  ArmDesign d;
  static_cast<ArmLengths&>(d) = plane.arms();
  d.fibres = o.fibres;
  return d;
}

RobotCalibration calibration_of(const RobotSite& r, const ArmLengths& arms) {
  RobotCalibration c;
  c.orientation_deg = r.orientation_deg;
  if (r.offsets) {
    c.alpha_offset_deg = r.offsets->alpha_deg;
    c.beta_offset_deg = r.offsets->beta_deg;
  }
  if (r.alpha_length_mm) c.alpha_length_delta_mm = *r.alpha_length_mm - arms.alpha_length_mm;
  if (r.beta_length_mm) c.beta_length_delta_mm = *r.beta_length_mm - arms.beta_tip_mm;
  for (const auto& f : r.fibre_offsets) c.fibres.push_back({std::string(fibre_name(f.fibre)), {f.x_mm, f.y_mm}});
  return c;
}

ModelSpec model_spec_from_layout(const FocalPlane& plane, const LayoutModelOptions& o) {
  ModelSpec m;
  m.robots.reserve(plane.robots().size());
  for (const auto& r : plane.robots()) {
    RobotSpec s;
    s.id = r.id;
    s.centre = {r.x_mm, r.y_mm};
    s.calibration = calibration_of(r, plane.arms());
    s.limits = o.limits;
    s.buffer_mm = o.buffer_mm;
    m.robots.push_back(std::move(s));
  }
  m.design = design_of(plane, o);
  for (const auto& f : plane.fiducials()) m.fiducials.push_back({f.id, {f.x_mm, f.y_mm}, o.fiducial_buffer_mm});
  for (const auto& g : plane.guide_cameras())
    m.obstacles.push_back({fmt::format("guide camera {}", g.id), {{g.x1_mm, g.y1_mm}, {g.x2_mm, g.y2_mm}}, g.buffer_mm});
  return m;
}

Result<CollisionModel> model_from_layout(const FocalPlane& plane, const LayoutModelOptions& o) {
  return CollisionModel::build(model_spec_from_layout(plane, o));
}

std::vector<bool> frozen_robots(const FocalPlane& plane) {
  std::vector<bool> out;
  out.reserve(plane.robots().size());
  for (const auto& r : plane.robots()) out.push_back(r.disabled || r.offline);
  return out;
}

}  // namespace axon::fps::plan
