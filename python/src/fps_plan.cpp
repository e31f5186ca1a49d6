// axon.fps: layouts (FocalPlane) and the planner (plan::plan_moves), with numpy arrays for poses
// and trajectories. plan() takes its inputs as `axon fps plan` does (folded, random with the
// seed, a target file, or poses), so the same input gives the same plan.json.
#include "bindings.hpp"

#include "axon/fps/layout/layout_file.hpp"
#include "axon/fps/layout/layout_generator.hpp"
#include "axon/fps/layout/layout_name.hpp"
#include "axon/fps/plan/layout_model.hpp"
#include "axon/fps/plan/plan_file.hpp"
#include "axon/fps/plan/planner.hpp"
#include "axon/fps/plan/problems.hpp"
#include "axon/fps/plan/targets.hpp"

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <fmt/format.h>

#include <memory>
#include <tuple>
#include <utility>

namespace axon::python {

namespace {

namespace plan = fps::plan;
using fps::FocalPlane;
using Poses = std::vector<plan::Pose>;

// An (n, 2) array whose row i is at(i) (a pair of doubles).
template <class At>
py::array_t<double> two_columns(std::size_t n, At at) {
  py::array_t<double> a({static_cast<py::ssize_t>(n), py::ssize_t{2}});
  auto v = a.mutable_unchecked<2>();
  for (std::size_t i = 0; i < n; ++i) std::tie(v(i, 0), v(i, 1)) = at(i);
  return a;
}

// Poses as rows of alpha, beta (degrees).
py::array_t<double> pose_array(const Poses& poses) {
  return two_columns(poses.size(), [&](std::size_t i) { return std::pair{poses[i].alpha_deg, poses[i].beta_deg}; });
}

// An arm's points as rows of degrees, seconds (as plan.json and Client.run_trajectories have them).
py::array_t<double> points_array(const std::vector<plan::TimedAngle>& points) {
  return two_columns(points.size(), [&](std::size_t i) { return std::pair{points[i].deg, points[i].t_s}; });
}

std::shared_ptr<plan::CollisionModel> model_of(const FocalPlane& layout, double buffer_mm) {
  plan::LayoutModelOptions o;
  o.buffer_mm = buffer_mm;
  return std::make_shared<plan::CollisionModel>(value_or_throw(plan::model_from_layout(layout, o)));
}

// {id: (alpha, beta)} as planner targets.
std::vector<plan::Target> targets_of(const py::dict& d) {
  std::vector<plan::Target> out;
  for (const auto& [key, value] : d) {
    const auto pair = value.cast<std::pair<double, double>>();
    plan::Target t;
    t.robot = key.cast<std::int32_t>();
    t.pose = plan::Pose{pair.first, pair.second};
    out.push_back(std::move(t));
  }
  return out;
}

// "folded", "random" (with `seed`), a target file, {id: (alpha, beta)} or an (N, 2) array in
// layout order: poses in model order, as `axon fps plan` reads --from and --to.
Poses poses_of(const plan::CollisionModel& model, const py::object& spec, std::uint64_t seed, plan::TargetPolicy policy) {
  if (py::isinstance<py::str>(spec)) {
    const auto text = spec.cast<std::string>();
    if (text == "folded") return plan::folded_poses(model);
    if (text == "random") return plan::random_poses(model, seed);
    return value_or_throw(plan::target_poses(model, value_or_throw(plan::load_targets(text)), policy));
  }
  if (py::isinstance<py::dict>(spec)) return value_or_throw(plan::target_poses(model, targets_of(spec), policy));
  const auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(spec);
  if (!a || a.ndim() != 2 || a.shape(1) != 2 || static_cast<std::size_t>(a.shape(0)) != model.size())
    throw Exception(Error(CoreErrc::invalid_argument,
                          fmt::format("poses: give 'folded', 'random', a target file, {{id: (alpha, beta)}} or an "
                                      "array of shape ({}, 2) (alpha, beta in degrees, layout order)",
                                      model.size())));
  const auto v = a.unchecked<2>();
  Poses out(model.size());
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = {v(i, 0), v(i, 1)};
  return out;
}

struct PlanResult {
  std::shared_ptr<plan::CollisionModel> model;
  plan::Plan plan;
  plan::PlannerOptions options;
  std::string layout_name;

  [[nodiscard]] std::size_t index(std::int32_t id) const {
    if (auto i = model->index_of(id)) return *i;
    throw py::key_error(fmt::format("robot {} is not in the layout", id));
  }
  [[nodiscard]] py::tuple trajectory(std::int32_t id) const {
    const auto& t = plan.trajectories.at(index(id));
    return py::make_tuple(points_array(t.alpha), points_array(t.beta));
  }
};

PlanResult run_plan(const FocalPlane& layout, const py::object& current, const py::object& target, std::uint64_t seed,
                    double speed_deg_s, double buffer_mm, bool reject) {
  PlanResult r{model_of(layout, buffer_mm), {}, {}, layout.name()};
  r.options.speed = {speed_deg_s, speed_deg_s};
  r.options.seed = seed;
  plan::PlanRequest req;
  req.current = poses_of(*r.model, current, seed + 1, plan::TargetPolicy::reject);
  req.target = poses_of(*r.model, target, seed, reject ? plan::TargetPolicy::reject : plan::TargetPolicy::park);
  req.frozen = plan::frozen_robots(layout);
  py::gil_scoped_release release;
  r.plan = value_or_throw(plan::plan_moves(*r.model, req, r.options));
  return r;
}

py::dict stats_of(const plan::PlanStats& s) {
  py::dict d;
  d["plan_s"] = s.plan_s;
  d["search_s"] = s.search_s;
  d["check_s"] = s.check_s;
  d["smooth_s"] = s.smooth_s;
  d["rounds"] = s.rounds;
  d["escapes"] = s.escapes;
  d["median_points"] = s.median_points;
  d["max_points"] = s.max_points;
  d["max_alpha_deg_s"] = s.max_alpha_speed;
  d["max_beta_deg_s"] = s.max_beta_speed;
  return d;
}

void bind_plan_result(py::module_& m) {
  py::class_<PlanResult>(m, "Plan", "A planned reconfiguration of the whole plane (what `axon fps plan` writes).")
      .def_property_readonly("verified", [](const PlanResult& r) { return r.plan.verified; },
                             "The independent checker found no contact.")
      .def_property_readonly("ok", [](const PlanResult& r) { return r.plan.ok(); })
      .def_property_readonly("not_reached", [](const PlanResult& r) { return r.plan.not_reached; })
      .def_property_readonly("duration_s", [](const PlanResult& r) { return r.plan.stats.duration_s; })
      .def_property_readonly("min_clearance_mm", [](const PlanResult& r) -> std::optional<double> {
        if (!r.plan.check.samples) return std::nullopt;
        return r.plan.check.min_clearance_mm;
      })
      .def_property_readonly("stats", [](const PlanResult& r) { return stats_of(r.plan.stats); },
                             "Timings (seconds) and counts of the planning.")
      .def_property_readonly("ids", [](const PlanResult& r) {
        py::array_t<std::int32_t> a(static_cast<py::ssize_t>(r.model->size()));
        for (std::size_t i = 0; i < r.model->size(); ++i) a.mutable_at(i) = r.model->robot(i).id();
        return a;
      })
      .def_property_readonly("status", [](const PlanResult& r) {
        std::vector<std::string> s;
        for (const auto& rp : r.plan.robots) s.emplace_back(plan::to_string(rp.status));
        return s;
      }, "Per robot, layout order: reached, frozen, parked or held.")
      .def_property_readonly("start", [](const PlanResult& r) {
        Poses p;
        for (const auto& t : r.plan.trajectories) p.push_back({t.alpha.front().deg, t.beta.front().deg});
        return pose_array(p);
      }, "(N, 2) alpha, beta in degrees where each robot starts, layout order.")
      .def_property_readonly("end", [](const PlanResult& r) {
        Poses p;
        for (const auto& rp : r.plan.robots) p.push_back(rp.end);
        return pose_array(p);
      }, "(N, 2) alpha, beta in degrees where the plan leaves each robot.")
      .def_property_readonly("reasons", [](const PlanResult& r) {
        py::dict d;
        for (std::size_t i = 0; i < r.plan.robots.size(); ++i)
          if (!r.plan.robots[i].reason.empty()) d[py::int_(r.model->robot(i).id())] = r.plan.robots[i].reason;
        return d;
      }, "{id: why} for the robots parked or held.")
      .def("trajectory", &PlanResult::trajectory, py::arg("id"),
           "(alpha, beta): arrays of points, columns degrees and seconds; the first point (0 s) is the start.")
      .def("to_json", [](const PlanResult& r) { return plan::plan_to_json(*r.model, r.plan, r.options, r.layout_name); },
           "plan.json, as `axon fps plan -o` writes it.")
      .def("summary", [](const PlanResult& r) { return r.plan.summary(*r.model); })
      .def("__repr__", [](const PlanResult& r) {
        return fmt::format("axon.fps.Plan({} robots, {} not reached, {:.1f} s move, {})", r.model->size(),
                           r.plan.not_reached, r.plan.stats.duration_s, r.plan.verified ? "verified" : "NOT verified");
      });
}

py::dict robot_columns(const FocalPlane& p) {
  const auto n = static_cast<py::ssize_t>(p.robots().size());
  py::array_t<std::uint16_t> id(n), gateway(n);
  py::array_t<double> x(n), y(n);
  py::array_t<std::int32_t> sextant(n), bus(n);
  py::array_t<bool> disabled(n), offline(n);
  for (py::ssize_t i = 0; i < n; ++i) {
    const auto& r = p.robots()[static_cast<std::size_t>(i)];
    id.mutable_at(i) = r.id;
    x.mutable_at(i) = r.x_mm;
    y.mutable_at(i) = r.y_mm;
    sextant.mutable_at(i) = r.sextant;
    gateway.mutable_at(i) = r.bus.gateway;
    bus.mutable_at(i) = r.bus.channel;
    disabled.mutable_at(i) = r.disabled;
    offline.mutable_at(i) = r.offline;
  }
  py::dict d;
  d["id"] = id;
  d["x_mm"] = x;
  d["y_mm"] = y;
  d["sextant"] = sextant;
  d["gateway"] = gateway;
  d["bus"] = bus;
  d["disabled"] = disabled;
  d["offline"] = offline;
  return d;
}

const fps::RobotSite& site(const FocalPlane& p, std::uint16_t id) {
  if (const auto* r = p.find(id)) return *r;
  throw py::key_error(fmt::format("robot {} is not in layout '{}'", id, p.name()));
}

void bind_layout(py::module_& m) {
  py::class_<FocalPlane, std::shared_ptr<FocalPlane>>(m, "Layout",
                                                      "A focal plane as built: robots (mm), buses, fiducials, neighbours.")
      .def_static("load", [](const std::string& name) { return value_or_throw(fps::resolve_layout(name)); },
                  py::arg("name"), "A layout file (YAML), or 'default' (500 robots) / 'benchtop' (6) as shipped.")
      .def_static("generate", [](int robots, const std::string& name, double pitch_mm, int fiducials_per_sextant,
                                 const std::string& gateway_address) {
             fps::LayoutGeneratorOptions o;
             o.robots = robots;
             o.name = name;
             o.pitch_mm = pitch_mm;
             o.fiducials_per_sextant = fiducials_per_sextant;
             o.gateway_address = gateway_address;
             return value_or_throw(fps::generate_layout(o));
           },
           py::kw_only(), py::arg("robots") = 500, py::arg("name") = "default", py::arg("pitch_mm") = fps::kDefaultPitchMm,
           py::arg("fiducials_per_sextant") = 10, py::arg("gateway_address") = "10.25.1.1{}:19228",
           "The generated telescope layout (498..504 robots in six sextants, four buses each).")
      .def_property_readonly("name", &FocalPlane::name)
      .def_property_readonly("pitch_mm", &FocalPlane::pitch_mm)
      .def("__len__", [](const FocalPlane& p) { return p.robots().size(); })
      .def("__contains__", [](const FocalPlane& p, std::uint16_t id) { return p.find(id) != nullptr; })
      .def("_robot_columns", &robot_columns)
      .def("fibres", [](const FocalPlane& p, std::uint16_t id) {
             std::vector<std::string> out;
             for (auto f : site(p, id).fibres) out.emplace_back(fps::fibre_name(f));
             return out;
           }, py::arg("id"))
      .def("neighbours", [](const FocalPlane& p, std::uint16_t id) { site(p, id); return p.neighbours(id).robots; },
           py::arg("id"), "Robots whose arms can touch this one's, nearest first.")
      .def("adjacent", [](const FocalPlane& p, std::uint16_t id) { site(p, id); return p.neighbours(id).adjacent; },
           py::arg("id"), "The robots right next to this one, nearest first.")
      .def_property_readonly("gateways", [](const FocalPlane& p) {
        std::map<std::uint16_t, std::string> out;
        for (const auto& g : p.gateways()) out[g.id] = g.address;
        return out;
      }, "{gateway id: 'HOST:PORT'}")
      .def_property_readonly("buses", [](const FocalPlane& p) {
        std::vector<std::string> out;
        for (const auto& b : p.buses()) out.push_back(b.to_string());
        return out;
      })
      .def("to_yaml", [](const FocalPlane& p) { return fps::to_yaml(p); }, "The layout file text.")
      .def("__repr__", [](const FocalPlane& p) {
        return fmt::format("axon.fps.Layout('{}', {} robots, {} buses)", p.name(), p.robots().size(), p.buses().size());
      });
}

}  // namespace

void bind_fps_plan(py::module_& m) {
  bind_layout(m);
  bind_plan_result(m);
  m.def("plan", &run_plan, py::arg("layout"), py::arg("current") = "folded", py::arg("target") = "random", py::kw_only(),
        py::arg("seed") = 1, py::arg("speed_deg_s") = 12.0, py::arg("buffer_mm") = 2.0, py::arg("reject") = false,
        "Collision-free trajectories for every robot from `current` to `target`, each 'folded', 'random' "
        "(current draws with seed + 1, target with seed, as `axon fps plan` does), a target file, "
        "{id: (alpha, beta)} or an (N, 2) array of degrees in layout order. Bad targets park their robot "
        "(reject=True: raise axon.fps.BadTarget). The GIL is released while it plans; Ctrl-C waits for the end.");
  m.def("random_poses", [](const FocalPlane& layout, std::uint64_t seed, double buffer_mm) {
          return pose_array(plan::random_poses(*model_of(layout, buffer_mm), seed));
        }, py::arg("layout"), py::arg("seed") = 1, py::arg("buffer_mm") = 2.0,
        "(N, 2) clear random poses, reproducible from the seed (layout order).");
  m.def("folded_poses", [](const FocalPlane& layout) { return pose_array(plan::folded_poses(*model_of(layout, 2.0))); },
        py::arg("layout"), "(N, 2): every robot at the folded pose (10, 170).");
}

}  // namespace axon::python
