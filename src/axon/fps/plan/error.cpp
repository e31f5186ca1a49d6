#include "axon/fps/plan/error.hpp"

namespace axon::fps::plan {
namespace {
class PlanCategory final : public std::error_category {
 public:
  const char* name() const noexcept override { return "axon.fps.plan"; }
  std::string message(int c) const override {
    switch (static_cast<PlanErrc>(c)) {
      case PlanErrc::too_close:
        return "target too close to the robot centre: the fibre cannot fold that far";
      case PlanErrc::too_far:
        return "target too far from the robot centre: beyond the fully extended arms";
      case PlanErrc::outside_hard_stops:
        return "target reachable only with angles outside the robot's hard-stop range";
      case PlanErrc::unknown_robot:
        return "unknown robot id: not part of the focal-plane layout";
      case PlanErrc::unknown_fibre:
        return "unknown fibre name: the beta arm carries no fibre of that name";
      case PlanErrc::duplicate_target:
        return "robot has more than one target";
      case PlanErrc::robot_collision:
        return "target pose collides with a neighbouring robot's beta arm";
      case PlanErrc::obstacle_collision:
        return "target pose collides with a fiducial or fixed obstacle";
      case PlanErrc::bad_target_file:
        return "target file cannot be read; see docs/fps-plan.md for the format";
      case PlanErrc::bad_trajectory:
        return "invalid trajectory: points need finite values and strictly increasing times";
      case PlanErrc::outside_safe_zone:
        return "targets outside their robots' safe zones: a robot within the arm tolerances may miss them or touch";
    }
    return "unknown fps planning error";
  }
};
}  // namespace

const std::error_category& plan_category() noexcept {
  static const PlanCategory c;
  return c;
}

}  // namespace axon::fps::plan
