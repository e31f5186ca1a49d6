#include "axon/fps/plan/layout_model.hpp"

namespace axon::fps::plan {

Result<CollisionModel> model_from_layout(const FocalPlane& plane, const LayoutModelOptions& o) {
  std::vector<RobotSpec> robots;
  robots.reserve(plane.robots().size());
  for (const auto& r : plane.robots()) {
    RobotSpec s;
    s.id = r.id;
    s.centre = {r.x_mm, r.y_mm};
    if (r.offsets) {
      s.calibration.alpha_offset_deg = r.offsets->alpha_deg;
      s.calibration.beta_offset_deg = r.offsets->beta_deg;
    }
    s.limits = o.limits;
    s.buffer_mm = o.buffer_mm;
    robots.push_back(s);
  }
  std::vector<FiducialSpec> fiducials;
  for (const auto& f : plane.fiducials()) fiducials.push_back({f.id, {f.x_mm, f.y_mm}, o.fiducial_buffer_mm});
  return CollisionModel::build(robots, o.design, fiducials);
}

std::vector<bool> frozen_robots(const FocalPlane& plane) {
  std::vector<bool> out;
  out.reserve(plane.robots().size());
  for (const auto& r : plane.robots()) out.push_back(r.disabled || r.offline);
  return out;
}

}  // namespace axon::fps::plan
