#include "axon/fps/plan/svg.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace axon::fps::plan {

namespace {

std::string escape(std::string_view s) {
  std::string out;
  for (const char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

// A capsule (segment + radius) as one closed path: two straight sides and two half circles.
std::string capsule_path(Segment s, double r) {
  const Vec2 d = s.b - s.a;
  const double len = norm(d);
  const Vec2 u = len > 0 ? (1.0 / len) * d : Vec2{1, 0};
  const Vec2 nrm{-u.y, u.x};
  const Vec2 p1 = s.a + r * nrm, p2 = s.b + r * nrm, p3 = s.b - r * nrm, p4 = s.a - r * nrm;
  return fmt::format("M {:.3f} {:.3f} L {:.3f} {:.3f} A {:.3f} {:.3f} 0 0 0 {:.3f} {:.3f} L {:.3f} {:.3f} "
                     "A {:.3f} {:.3f} 0 0 0 {:.3f} {:.3f} Z",
                     p1.x, p1.y, p2.x, p2.y, r, r, p3.x, p3.y, p4.x, p4.y, r, r, p1.x, p1.y);
}

}  // namespace

std::vector<SvgPath> fibre_paths(const CollisionModel& model, std::span<const RobotTrajectory> trajectories,
                                 std::size_t fibre, double step_s) {
  std::vector<SvgPath> out;
  if (!(step_s > 0)) return out;
  for (std::size_t i = 0; i < std::min(model.size(), trajectories.size()); ++i) {
    const RobotTrajectory& t = trajectories[i];
    if (t.alpha.empty() || t.beta.empty()) continue;
    if (max_speed(t.alpha) == 0 && max_speed(t.beta) == 0) continue;
    const double t0 = std::min(t.alpha.front().t_s, t.beta.front().t_s);
    const double t1 = std::max(t.alpha.back().t_s, t.beta.back().t_s);
    SvgPath p{i, {}};
    const auto steps = static_cast<std::size_t>(std::ceil((t1 - t0) / step_s));
    for (std::size_t k = 0; k <= steps; ++k) {
      const double tt = std::min(t1, t0 + static_cast<double>(k) * step_s);
      p.points.push_back(model.robot(i).fibre({angle_at(t.alpha, tt), angle_at(t.beta, tt)}, fibre));
    }
    out.push_back(std::move(p));
  }
  return out;
}

std::string render_svg(const CollisionModel& model, std::span<const Pose> poses, const SvgOptions& o,
                       std::span<const SvgPath> paths, std::span<const Contact> contacts) {
  // Bounds of everything drawn, in mm.
  double xmin = std::numeric_limits<double>::infinity(), ymin = xmin, xmax = -xmin, ymax = -xmin;
  auto grow = [&](Vec2 p) {
    xmin = std::min(xmin, p.x), xmax = std::max(xmax, p.x);
    ymin = std::min(ymin, p.y), ymax = std::max(ymax, p.y);
  };
  for (const auto& r : model.robots()) grow(r.centre());
  for (const auto& ob : model.obstacles()) grow(ob.shape.a), grow(ob.shape.b);
  if (!(xmin <= xmax)) xmin = ymin = -1, xmax = ymax = 1;
  xmin -= o.margin_mm, ymin -= o.margin_mm, xmax += o.margin_mm, ymax += o.margin_mm;
  const double w = xmax - xmin, h = ymax - ymin;

  std::string s;
  s += "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  // The viewBox is in mm with y flipped by a group transform; stroke widths are in mm too.
  s += fmt::format("<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"{:.0f}\" height=\"{:.0f}\" "
                   "viewBox=\"{:.3f} {:.3f} {:.3f} {:.3f}\">\n",
                   w * o.px_per_mm, h * o.px_per_mm, xmin, -ymax, w, h);
  if (!o.title.empty()) s += fmt::format("<title>{}</title>\n", escape(o.title));
  s += "<rect x=\"" + fmt::format("{:.3f}", xmin) + "\" y=\"" + fmt::format("{:.3f}", -ymax) + "\" width=\"" +
       fmt::format("{:.3f}", w) + "\" height=\"" + fmt::format("{:.3f}", h) + "\" fill=\"white\"/>\n";
  s += "<g transform=\"scale(1,-1)\">\n";

  if (o.patrol && model.design().fibres.size() > 0) {
    s += "<g id=\"patrol\" fill=\"none\" stroke=\"#cccccc\" stroke-width=\"0.1\">\n";
    for (const auto& r : model.robots())
      s += fmt::format("<circle cx=\"{:.3f}\" cy=\"{:.3f}\" r=\"{:.3f}\"/>\n", r.centre().x, r.centre().y,
                       r.max_reach_mm(0));
    s += "</g>\n";
  }

  s += "<g id=\"obstacles\" fill=\"#6fa8dc\" fill-opacity=\"0.5\" stroke=\"#1c4587\" stroke-width=\"0.15\">\n";
  for (const auto& ob : model.obstacles()) s += fmt::format("<path d=\"{}\"/>\n", capsule_path(ob.shape, ob.buffer_mm));
  s += "</g>\n";

  const std::size_t n = std::min(model.size(), poses.size());
  std::vector<Segment> segs(model.size());
  for (std::size_t i = 0; i < n; ++i) segs[i] = model.robot(i).collision_segment(poses[i]);
  if (o.buffers) {
    s += "<g id=\"buffers\" fill=\"#f9cb9c\" fill-opacity=\"0.5\" stroke=\"#b45f06\" stroke-width=\"0.1\">\n";
    for (std::size_t i = 0; i < n; ++i)
      s += fmt::format("<path d=\"{}\"/>\n", capsule_path(segs[i], model.robot(i).buffer_mm()));
    s += "</g>\n";
  }

  s += "<g id=\"robots\" stroke-linecap=\"round\">\n";
  for (std::size_t i = 0; i < model.size(); ++i) {
    const Positioner& r = model.robot(i);
    s += fmt::format("<circle cx=\"{:.3f}\" cy=\"{:.3f}\" r=\"0.6\" fill=\"black\"/>\n", r.centre().x, r.centre().y);
    if (i >= n) continue;
    const Vec2 axis = r.beta_axis(poses[i]);
    const Vec2 tip = r.tip(poses[i]);
    s += fmt::format("<line x1=\"{:.3f}\" y1=\"{:.3f}\" x2=\"{:.3f}\" y2=\"{:.3f}\" stroke=\"#444444\" "
                     "stroke-width=\"1.0\"/>\n",
                     r.centre().x, r.centre().y, axis.x, axis.y);
    s += fmt::format("<line x1=\"{:.3f}\" y1=\"{:.3f}\" x2=\"{:.3f}\" y2=\"{:.3f}\" stroke=\"black\" "
                     "stroke-width=\"0.8\"/>\n",
                     axis.x, axis.y, tip.x, tip.y);
    for (std::size_t f = 0; f < r.fibre_count(); ++f) {
      const Vec2 p = r.fibre(poses[i], f);
      s += fmt::format("<circle cx=\"{:.3f}\" cy=\"{:.3f}\" r=\"0.2\" fill=\"#3c78d8\"/>\n", p.x, p.y);
    }
  }
  s += "</g>\n";

  if (!paths.empty()) {
    s += "<g id=\"paths\" fill=\"none\" stroke=\"#6aa84f\" stroke-width=\"0.2\">\n";
    for (const auto& p : paths) {
      if (p.points.empty()) continue;
      std::string pts;
      for (const Vec2 q : p.points) pts += fmt::format("{:.3f},{:.3f} ", q.x, q.y);
      if (!pts.empty()) pts.pop_back();
      s += fmt::format("<polyline points=\"{}\"/>\n", pts);
    }
    s += "</g>\n";
  }

  if (!contacts.empty()) {
    s += "<g id=\"contacts\" stroke=\"red\" stroke-width=\"0.4\" fill=\"none\">\n";
    for (const auto& c : contacts) {
      if (c.a >= n) continue;
      if (c.kind == Contact::Kind::robot && c.b < n)
        s += fmt::format("<path d=\"{}\"/>\n<path d=\"{}\"/>\n", capsule_path(segs[c.a], model.robot(c.a).buffer_mm()),
                         capsule_path(segs[c.b], model.robot(c.b).buffer_mm()));
      else if (c.kind == Contact::Kind::obstacle && c.b < model.obstacles().size())
        s += fmt::format("<path d=\"{}\"/>\n<path d=\"{}\"/>\n", capsule_path(segs[c.a], model.robot(c.a).buffer_mm()),
                         capsule_path(model.obstacles()[c.b].shape, model.obstacles()[c.b].buffer_mm));
    }
    s += "</g>\n";
  }
  s += "</g>\n";

  if (o.labels) {
    // Text outside the flipped group so it reads upright.
    s += "<g id=\"labels\" font-family=\"sans-serif\" font-size=\"3\" fill=\"#333333\">\n";
    for (const auto& r : model.robots())
      s += fmt::format("<text x=\"{:.3f}\" y=\"{:.3f}\">{}</text>\n", r.centre().x + 1, -r.centre().y - 1, r.id());
    s += "</g>\n";
  }
  s += "</svg>\n";
  return s;
}

}  // namespace axon::fps::plan
