#include "axon/fps/plan/stepper.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <numeric>

namespace axon::fps::plan {

namespace {

constexpr int kMaxDepth = 8;          // halvings per step and pair
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kClrW = 1.0;   // escape score: clearance opened (mm, capped at 5)
constexpr double kKeepW = 0.5;  // escape score: bonus for keeping the direction (fewer corners)

Pose lerp(Pose a, Pose b, double f) noexcept {
  return {a.alpha_deg + f * (b.alpha_deg - a.alpha_deg), a.beta_deg + f * (b.beta_deg - a.beta_deg)};
}

Vec2 mid(const Segment& s) noexcept { return 0.5 * (s.a + s.b); }

// One arm's new angle: lands exactly on the goal when the step reaches it.
double advance(double from, double delta, double goal) noexcept {
  const double to = from + delta;
  return std::abs(to - goal) < 1e-9 ? goal : to;
}

struct Move {
  double da = 0;
  double db = 0;
  friend bool operator==(const Move&, const Move&) = default;
};

Pose apply(Pose p, Move mv, Pose goal) noexcept {
  return {advance(p.alpha_deg, mv.da, goal.alpha_deg), advance(p.beta_deg, mv.db, goal.beta_deg)};
}

// A robot's move over one (sub-)step: its poses and collision segments at both ends.
struct Motion {
  Pose p0, p1;
  Segment s0, s1;
};

// The collision segment of robot r at the pose half-way between a motion's two (both angles
// lerped): while each arm's direction turns by less than a half circle, its direction there is
// the bisector of its directions at the ends, so no sine or cosine is needed. A turn of a quarter
// circle or more (no engine step turns that much) is computed from the pose instead.
Segment half_way(const Positioner& r, const Motion& m) noexcept {
  const double turn_a = m.p1.alpha_deg - m.p0.alpha_deg, turn_b = turn_a + (m.p1.beta_deg - m.p0.beta_deg);
  if (std::abs(turn_a) >= 90 || std::abs(turn_b) >= 90) return r.collision_segment(lerp(m.p0, m.p1, 0.5));
  const Vec2 c = r.centre();
  const Vec2 ua = (m.s0.a - c) + (m.s1.a - c), ub = (m.s0.b - m.s0.a) + (m.s1.b - m.s1.a);
  const Vec2 axis = c + (r.alpha_length_mm() / norm(ua)) * ua;
  return {axis, axis + (r.collision_length_mm() / norm(ub)) * ub};
}

// A motion's two halves (the first's end, the second's start: the half-way pose and segment).
std::pair<Motion, Motion> halves(const Positioner& r, const Motion& m) noexcept {
  const Pose pm = lerp(m.p0, m.p1, 0.5);
  const Segment sm = half_way(r, m);
  return {{m.p0, pm, m.s0, sm}, {pm, m.p1, sm, m.s1}};
}

struct ArmRecorder {
  std::vector<TimedAngle> points;
  double last_delta = 0;
};

struct RobotState {
  double best_cost = kInf;
  int stuck = 0;
  int escape_left = 0;
  double best_ever = kInf;  // lowest cost reached so far
  int fruitless = 0;        // escapes of its own since best_ever last improved
  bool gave_up = false;     // stands still for the rest of the run
  Move last{};
  ArmRecorder alpha, beta;
};

class Stepper {
 public:
  Stepper(const CollisionModel& model, std::span<const StepperRobot> robots, const StepperOptions& o)
      : m_(model), robots_(robots), o_(o), rng_(o.seed) {}

  StepperResult run();

 private:
  struct Feasibility {
    bool ok = true;
    double min_clearance = kInf;  // after the move (exact where it is small)
  };

  [[nodiscard]] double direct_cost(std::size_t i, Pose p) const noexcept {
    const Pose g = robots_[i].goal;
    return o_.alpha_weight * std::abs(g.alpha_deg - p.alpha_deg) + o_.beta_weight * std::abs(g.beta_deg - p.beta_deg);
  }
  [[nodiscard]] double cost(std::size_t i, Pose p) const noexcept {
    return fields_.empty() || fields_[i].cost.empty() ? direct_cost(i, p) : field_cost(i, p);
  }
  // Navigation field of one robot: the cost to its goal around the fixed obstacles and the robots
  // that never move, on a grid of engine steps anchored at the goal (Dijkstra with the cost's
  // weights). Built when a robot gets stuck next to something fixed; a robot that follows it
  // downhill cannot get caught in a pocket of fixed obstacles.
  struct Field {
    std::vector<float> cost;  // na * nb, +inf where blocked or cut off
    int na = 0, nb = 0, oa = 0, ob = 0;
  };
  [[nodiscard]] double field_cost(std::size_t i, Pose p) const noexcept;
  bool build_field(std::size_t i);
  [[nodiscard]] double travel(std::size_t i, Move mv) const noexcept {
    const Positioner& r = m_.robot(i);
    return (std::abs(mv.da) * r.reach_mm() + std::abs(mv.db) * r.collision_length_mm()) * kRad;
  }
  // Robot i's collision segment after move `mv` from its pose of this step's start, landing on
  // q = apply(prev, mv, goal): a full step of each arm (or none) turns the start's segment by the
  // step's precomputed rotations (no sine or cosine: the candidates of a step are most of the
  // engine's trigonometry); a partial step, or one that snapped onto the goal, is computed anew.
  [[nodiscard]] Segment moved_segment(std::size_t i, Move mv, Pose q) const noexcept;
  bool certify(std::size_t i, const Motion& mi, double ci0, double ci1, std::size_t j, const Motion& mj, double limit,
               double s, int depth);
  bool certify_obstacle(std::size_t i, const Motion& mi, double c0, double c1, const Segment& ob, double limit,
                        double s, int depth);
  Feasibility feasible(std::size_t i, Pose p1, const Segment& s1, double trav, bool want_clearance,
                       std::vector<std::uint32_t>* blockers);
  void step_robot(std::size_t i);
  void record(std::size_t i, double t_s);
  // With scripts: a planned robot about to stand still checks that no scripted neighbour runs
  // into it, and otherwise takes the clear move that keeps the most clearance.
  bool scripted_neighbour_moves(std::size_t i) const noexcept;
  void hold_or_dodge(std::size_t i);

  const CollisionModel& m_;
  std::span<const StepperRobot> robots_;
  StepperOptions o_;
  std::mt19937_64 rng_;
  std::vector<Pose> prev_, cur_;
  std::vector<Segment> seg_prev_, seg_cur_;
  std::vector<double> trav_;
  std::vector<RobotState> st_;
  std::size_t escapes_ = 0;
  std::size_t checks_ = 0;
  std::vector<std::uint32_t> rank_;      // priority: higher ranks do not make way for lower
  std::vector<std::uint32_t> blockers_;  // scratch
  std::vector<bool> is_scripted_;
  std::vector<Field> fields_;
  std::vector<bool> field_tried_;
  bool has_scripts_ = false;
  std::size_t violations_ = 0;
  // {cos, sin} of the alpha step's turns (-1, 0, +1 steps) and of the beta arm's direction's turns
  // (alpha's plus beta's), for moved_segment.
  std::array<Vec2, 3> turn_alpha_{};
  std::array<std::array<Vec2, 3>, 3> turn_beta_{};
};

// -1, 0, +1 as an index 0..2 when `d` is exactly no step or one full step; -1 otherwise.
int step_index(double d, double step) noexcept {
  if (d == 0) return 1;
  if (d == step) return 2;
  if (d == -step) return 0;
  return -1;
}

Segment Stepper::moved_segment(std::size_t i, Move mv, Pose q) const noexcept {
  const Pose p = prev_[i];
  const Positioner& r = m_.robot(i);
  const int ka = step_index(mv.da, o_.alpha_step_deg), kb = step_index(mv.db, o_.beta_step_deg);
  if (ka < 0 || kb < 0 || q.alpha_deg != p.alpha_deg + mv.da || q.beta_deg != p.beta_deg + mv.db)
    return r.collision_segment(q);
  if (ka == 1 && kb == 1) return seg_prev_[i];
  const Segment& s0 = seg_prev_[i];
  const Vec2 ua = (1.0 / r.alpha_length_mm()) * (s0.a - r.centre());
  const Vec2 ub = (1.0 / r.collision_length_mm()) * (s0.b - s0.a);
  const Vec2 ta = turn_alpha_[static_cast<std::size_t>(ka)];
  const Vec2 tb = turn_beta_[static_cast<std::size_t>(ka)][static_cast<std::size_t>(kb)];
  const Vec2 axis = r.centre() + r.alpha_length_mm() * rotate(ua, ta.x, ta.y);
  return {axis, axis + r.collision_length_mm() * rotate(ub, tb.x, tb.y)};
}

double Stepper::field_cost(std::size_t i, Pose p) const noexcept {
  const Field& f = fields_[i];
  const Pose g = robots_[i].goal;
  const double fa = (p.alpha_deg - g.alpha_deg) / o_.alpha_step_deg + f.oa;
  const double fb = (p.beta_deg - g.beta_deg) / o_.beta_step_deg + f.ob;
  const int ca = static_cast<int>(std::lround(fa)), cb = static_cast<int>(std::lround(fb));
  double best = kInf;
  // The cheapest of the nearby cells plus the straight way there: exactly 0 only at the goal.
  for (int a = ca - 1; a <= ca + 1; ++a)
    for (int b = cb - 1; b <= cb + 1; ++b) {
      if (a < 0 || b < 0 || a >= f.na || b >= f.nb) continue;
      const double c = f.cost[static_cast<std::size_t>(a) * static_cast<std::size_t>(f.nb) + static_cast<std::size_t>(b)];
      if (!(c < kInf)) continue;
      best = std::min(best, c + o_.alpha_weight * std::abs(fa - a) * o_.alpha_step_deg +
                                o_.beta_weight * std::abs(fb - b) * o_.beta_step_deg);
    }
  return best < kInf ? best : 1e6 + direct_cost(i, p);
}

bool Stepper::build_field(std::size_t i) {
  field_tried_[i] = true;
  const Positioner& r = m_.robot(i);
  const AngleLimits& lim = r.limits();
  const Pose g = robots_[i].goal;
  const double sa = o_.alpha_step_deg, sb = o_.beta_step_deg;
  Field f;
  f.oa = static_cast<int>(std::floor((g.alpha_deg - lim.alpha_min_deg) / sa + 1e-9));
  f.ob = static_cast<int>(std::floor((g.beta_deg - lim.beta_min_deg) / sb + 1e-9));
  f.na = f.oa + static_cast<int>(std::floor((lim.alpha_max_deg - g.alpha_deg) / sa + 1e-9)) + 1;
  f.nb = f.ob + static_cast<int>(std::floor((lim.beta_max_deg - g.beta_deg) / sb + 1e-9)) + 1;
  if (f.na <= 0 || f.nb <= 0 || static_cast<long>(f.na) * f.nb > 4'000'000) return false;
  // What is fixed: obstacles and the neighbours that never move.
  struct Fixed {
    Segment s;
    double limit;
  };
  std::vector<Fixed> fixed;
  const auto obstacles = m_.obstacles();
  const auto opairs = m_.obstacle_pairs();
  for (const std::uint32_t k : m_.obstacle_pairs_of(i))
    fixed.push_back({obstacles[opairs[k].obstacle].shape, opairs[k].limit_mm});
  const auto nb = m_.neighbours(i);
  const auto pairs = m_.pairs_of(i);
  const auto all_pairs = m_.robot_pairs();
  for (std::size_t k = 0; k < nb.size(); ++k)
    if (robots_[nb[k]].frozen) fixed.push_back({seg_prev_[nb[k]], all_pairs[pairs[k]].limit_mm});
  if (fixed.empty()) return false;
  const std::size_t cells = static_cast<std::size_t>(f.na) * static_cast<std::size_t>(f.nb);
  std::vector<std::uint8_t> blocked(cells, 0);
  for (int a = 0; a < f.na; ++a)
    for (int b = 0; b < f.nb; ++b) {
      const Pose q{g.alpha_deg + (a - f.oa) * sa, g.beta_deg + (b - f.ob) * sb};
      const Segment sq = r.collision_segment(q);
      for (const Fixed& x : fixed)
        if (segment_distance(sq, x.s) < x.limit + o_.margin_mm) {
          blocked[static_cast<std::size_t>(a) * static_cast<std::size_t>(f.nb) + static_cast<std::size_t>(b)] = 1;
          break;
        }
    }
  f.cost.assign(cells, std::numeric_limits<float>::infinity());
  using Item = std::pair<float, std::uint32_t>;
  std::vector<Item> heap;
  const std::size_t goal_cell = static_cast<std::size_t>(f.oa) * static_cast<std::size_t>(f.nb) + static_cast<std::size_t>(f.ob);
  if (blocked[goal_cell]) return false;
  f.cost[goal_cell] = 0;
  heap.push_back({0.0f, static_cast<std::uint32_t>(goal_cell)});
  const float wa = static_cast<float>(o_.alpha_weight * sa), wb = static_cast<float>(o_.beta_weight * sb);
  auto greater = [](const Item& x, const Item& y) { return x.first > y.first; };
  while (!heap.empty()) {
    std::pop_heap(heap.begin(), heap.end(), greater);
    const auto [c, cell] = heap.back();
    heap.pop_back();
    if (c > f.cost[cell]) continue;
    const int a = static_cast<int>(cell / static_cast<std::uint32_t>(f.nb)), b = static_cast<int>(cell % static_cast<std::uint32_t>(f.nb));
    for (int da = -1; da <= 1; ++da)
      for (int db = -1; db <= 1; ++db) {
        if (da == 0 && db == 0) continue;
        const int a2 = a + da, b2 = b + db;
        if (a2 < 0 || b2 < 0 || a2 >= f.na || b2 >= f.nb) continue;
        const std::size_t c2 = static_cast<std::size_t>(a2) * static_cast<std::size_t>(f.nb) + static_cast<std::size_t>(b2);
        if (blocked[c2]) continue;
        const float nc = c + (da != 0 ? wa : 0.0f) + (db != 0 ? wb : 0.0f);
        if (nc < f.cost[c2]) {
          f.cost[c2] = nc;
          heap.push_back({nc, static_cast<std::uint32_t>(c2)});
          std::push_heap(heap.begin(), heap.end(), greater);
        }
      }
  }
  fields_[i] = std::move(f);
  // Useless when the robot's own cell is cut off from the goal.
  if (!(field_cost(i, prev_[i]) < 1e6)) {
    fields_[i] = {};
    return false;
  }
  return true;
}

bool Stepper::scripted_neighbour_moves(std::size_t i) const noexcept {
  for (const std::uint32_t j : m_.neighbours(i))
    if (is_scripted_[j] && cur_[j] != prev_[j]) return true;
  return false;
}

void Stepper::hold_or_dodge(std::size_t i) {
  if (!scripted_neighbour_moves(i)) return;
  const Pose p = prev_[i];
  if (feasible(i, p, seg_prev_[i], 0.0, false, nullptr).ok) return;
  const AngleLimits& lim = m_.robot(i).limits();
  double best = -kInf;
  Move chosen{};
  bool found = false;
  for (double a : {-o_.alpha_step_deg, 0.0, o_.alpha_step_deg})
    for (double b : {-o_.beta_step_deg, 0.0, o_.beta_step_deg}) {
      const Move mv{a, b};
      if (mv == Move{}) continue;
      const Pose q{p.alpha_deg + a, p.beta_deg + b};
      if (q.alpha_deg < lim.alpha_min_deg || q.alpha_deg > lim.alpha_max_deg || q.beta_deg < lim.beta_min_deg ||
          q.beta_deg > lim.beta_max_deg)
        continue;
      const auto f = feasible(i, q, moved_segment(i, mv, q), travel(i, mv), true, nullptr);
      if (f.ok && f.min_clearance > best) {
        best = f.min_clearance;
        chosen = mv;
        found = true;
      }
    }
  if (!found) {
    ++violations_;
    return;
  }
  const Pose q{p.alpha_deg + chosen.da, p.beta_deg + chosen.db};
  cur_[i] = q;
  seg_cur_[i] = moved_segment(i, chosen, q);
  trav_[i] = travel(i, chosen);
  st_[i].last = chosen;
}

bool Stepper::certify(std::size_t i, const Motion& mi, double c0, double c1, std::size_t j, const Motion& mj,
                      double limit, double s, int depth) {
  if (c0 + c1 - s >= 2 * kCertifyTinyMm) return true;
  if (c0 < 0 || c1 < 0) return false;
  if (s <= kCertifyResolutionMm) return true;  // a dip of at most kCertifyResolutionMm / 2 between two clear samples
  if (depth >= kMaxDepth) return false;
  const auto [i0, i1] = halves(m_.robot(i), mi);
  const auto [j0, j1] = halves(m_.robot(j), mj);
  const double cm = segment_distance(i0.s1, j0.s1) - limit;
  ++checks_;
  return certify(i, i0, c0, cm, j, j0, limit, s / 2, depth + 1) && certify(i, i1, cm, c1, j, j1, limit, s / 2, depth + 1);
}

bool Stepper::certify_obstacle(std::size_t i, const Motion& mi, double c0, double c1, const Segment& ob, double limit,
                               double s, int depth) {
  if (c0 + c1 - s >= 2 * kCertifyTinyMm) return true;
  if (c0 < 0 || c1 < 0) return false;
  if (s <= kCertifyResolutionMm) return true;
  if (depth >= kMaxDepth) return false;
  const auto [i0, i1] = halves(m_.robot(i), mi);
  const double cm = segment_distance(i0.s1, ob) - limit;
  return certify_obstacle(i, i0, c0, cm, ob, limit, s / 2, depth + 1) &&
         certify_obstacle(i, i1, cm, c1, ob, limit, s / 2, depth + 1);
}

Stepper::Feasibility Stepper::feasible(std::size_t i, Pose p1, const Segment& s1, double trav, bool want_clearance,
                                       std::vector<std::uint32_t>* blockers) {
  Feasibility f;
  const Positioner& ri = m_.robot(i);
  const Segment& s0 = seg_prev_[i];
  const Pose p0 = prev_[i];
  const double hi = 0.5 * ri.collision_length_mm();
  const auto nb = m_.neighbours(i);
  const auto pairs = m_.pairs_of(i);
  const auto all_pairs = m_.robot_pairs();
  for (std::size_t k = 0; k < nb.size(); ++k) {
    const std::size_t j = nb[k];
    const double limit = all_pairs[pairs[k]].limit_mm;
    const Segment& sj0 = seg_prev_[j];
    const Segment& sj1 = seg_cur_[j];
    const double s = trav + trav_[j];
    const double hj = 0.5 * m_.robot(j).collision_length_mm();
    // Lower bounds from the segments' midpoints: enough for the pairs that are far apart.
    const double lb0 = norm(mid(s0) - mid(sj0)) - hi - hj - limit;
    const double lb1 = norm(mid(s1) - mid(sj1)) - hi - hj - limit;
    if (lb1 >= o_.margin_mm && lb0 + lb1 - s >= 2 * kCertifyTinyMm && (!want_clearance || lb1 >= 5.0)) {
      f.min_clearance = std::min(f.min_clearance, lb1);
      continue;
    }
    ++checks_;
    const double c0 = segment_distance(s0, sj0) - limit;
    const double c1 = segment_distance(s1, sj1) - limit;
    f.min_clearance = std::min(f.min_clearance, c1);
    const bool ok = c1 >= std::min(o_.margin_mm, c0) &&
                    certify(i, {p0, p1, s0, s1}, c0, c1, j, {prev_[j], cur_[j], sj0, sj1}, limit, s, 0);
    if (!ok) {
      f.ok = false;
      if (blockers) blockers->push_back(static_cast<std::uint32_t>(j));
      else if (!want_clearance) return f;
    }
  }
  const auto obstacles = m_.obstacles();
  const auto opairs = m_.obstacle_pairs();
  for (const std::uint32_t k : m_.obstacle_pairs_of(i)) {
    const ObstaclePair& op = opairs[k];
    const Segment& ob = obstacles[op.obstacle].shape;
    const double c1 = segment_distance(s1, ob) - op.limit_mm;
    f.min_clearance = std::min(f.min_clearance, c1);
    if (c1 >= 2 * trav + o_.margin_mm + 2 * kCertifyTinyMm) continue;  // c0 >= c1 - trav
    const double c0 = segment_distance(s0, ob) - op.limit_mm;
    if (!(c1 >= std::min(o_.margin_mm, c0) && certify_obstacle(i, {p0, p1, s0, s1}, c0, c1, ob, op.limit_mm, trav, 0))) {
      f.ok = false;
      if (!want_clearance && !blockers) return f;
    }
  }
  return f;
}

void Stepper::step_robot(std::size_t i) {
  const StepperRobot& r = robots_[i];
  RobotState& st = st_[i];
  const Pose p = prev_[i];
  const Pose g = r.goal;
  const double now = cost(i, p);
  if ((now == 0 && st.escape_left == 0) || st.gave_up) {
    if (has_scripts_) hold_or_dodge(i);
    return;
  }
  const AngleLimits& lim = m_.robot(i).limits();

  const double rem_a = g.alpha_deg - p.alpha_deg, rem_b = g.beta_deg - p.beta_deg;
  std::array<double, 3> da{0, 0, 0}, db{0, 0, 0};
  auto options = [](double rem, double step, std::array<double, 3>& out) {
    if (rem == 0) {
      out = {0.0, step, -step};
    } else {
      const double sg = rem > 0 ? 1.0 : -1.0;
      out = {sg * std::min(step, std::abs(rem)), 0.0, -sg * step};
    }
  };
  options(rem_a, o_.alpha_step_deg, da);
  options(rem_b, o_.beta_step_deg, db);

  struct Candidate {
    Move mv;
    double score = 0;
  };
  std::array<Candidate, 9> cands;
  std::size_t nc = 0;
  const bool escaping = st.escape_left > 0;
  for (double a : da)
    for (double b : db) {
      const Move mv{a, b};
      if (mv == Move{}) continue;
      const Pose q = apply(p, mv, g);
      if (q.alpha_deg < lim.alpha_min_deg || q.alpha_deg > lim.alpha_max_deg || q.beta_deg < lim.beta_min_deg ||
          q.beta_deg > lim.beta_max_deg)
        continue;
      const double c = cost(i, q);
      if (!escaping && c >= now - 1e-12) continue;
      // Ties go to the previous move: fewer corners in the trajectory.
      cands[nc++] = {mv, c - (mv == st.last ? 1e-9 : 0.0)};
    }

  Move chosen{};
  Segment chosen_seg{};  // the segment at the chosen move's end (set with `chosen`)
  if (!escaping) {
    // Insertion sort: at most eight candidates.
    for (std::size_t a = 1; a < nc; ++a)
      for (std::size_t b = a; b > 0 && cands[b].score < cands[b - 1].score; --b) std::swap(cands[b], cands[b - 1]);
    for (std::size_t k = 0; k < nc; ++k) {
      const Pose q = apply(p, cands[k].mv, g);
      const Segment s1 = moved_segment(i, cands[k].mv, q);
      if (feasible(i, q, s1, travel(i, cands[k].mv), false, nullptr).ok) {
        chosen = cands[k].mv;
        chosen_seg = s1;
        break;
      }
    }
  } else {
    std::uniform_real_distribution<double> noise(0.0, 1.0);
    double best = -kInf;
    for (std::size_t k = 0; k < nc; ++k) {
      const Pose q = apply(p, cands[k].mv, g);
      const Segment s1 = moved_segment(i, cands[k].mv, q);
      const auto f = feasible(i, q, s1, travel(i, cands[k].mv), true, nullptr);
      if (!f.ok) continue;
      double score = kClrW * std::min(f.min_clearance, 5.0) + noise(rng_) + (cands[k].mv == st.last ? kKeepW : 0.0);
      // Keep away from the alpha stops while unfolded: a robot pushed against one has only one
      // way to turn and gets caught in pockets there.
      if (o_.stop_avoid_deg > 0 && q.beta_deg < 150) {
        const double to_stop = std::min(q.alpha_deg - lim.alpha_min_deg, lim.alpha_max_deg - q.alpha_deg);
        if (to_stop < o_.stop_avoid_deg) score -= 2.0 * (1.0 - to_stop / o_.stop_avoid_deg);
      }
      if (score > best) {
        best = score;
        chosen = cands[k].mv;
        chosen_seg = s1;
      }
    }
    if (--st.escape_left == 0) {
      st.stuck = 0;
      st.best_cost = kInf;
    }
  }

  const Pose q = apply(p, chosen, g);
  cur_[i] = q;
  seg_cur_[i] = chosen == Move{} ? moved_segment(i, chosen, q) : chosen_seg;
  trav_[i] = travel(i, chosen);
  st.last = chosen;
  if (chosen == Move{} && has_scripts_) hold_or_dodge(i);
  if (escaping) return;
  const double after = cost(i, q);
  if (after < st.best_ever - 1e-9) {
    st.best_ever = after;
    st.fruitless = 0;
  }
  if (after < st.best_cost - 1e-9) {
    st.best_cost = after;
    st.stuck = 0;
  } else if (++st.stuck >= o_.stuck_steps) {
    if (o_.fields && !field_tried_[i] && build_field(i)) {
      // From now on it follows the field: a fresh start of its progress count.
      st.stuck = 0;
      st.best_cost = cost(i, q);
      return;
    }
    std::uniform_int_distribution<int> len(o_.escape_min_steps, std::max(o_.escape_min_steps, o_.escape_max_steps));
    st.stuck = 0;
    // Blockers of lower priority make way; only when every blocker ranks higher does this robot
    // step aside itself.
    bool yielded = false;
    if (nc > 0) {
      blockers_.clear();
      const Pose q0 = apply(p, cands[0].mv, g);
      feasible(i, q0, moved_segment(i, cands[0].mv, q0), travel(i, cands[0].mv), false, &blockers_);
      for (const std::uint32_t j : blockers_) {
        if (robots_[j].frozen || rank_[j] >= rank_[i] || st_[j].escape_left > 0 || st_[j].gave_up) continue;
        st_[j].escape_left = len(rng_);
        ++escapes_;
        yielded = true;
      }
    }
    if (!yielded) {
      if (o_.give_up_after > 0 && ++st.fruitless >= o_.give_up_after) {
        st.gave_up = true;  // its oscillations only add corners and time: left to the untangle
        return;
      }
      st.escape_left = len(rng_);
      ++escapes_;
    }
  }
}

void Stepper::record(std::size_t i, double t_s) {
  auto arm = [t_s](ArmRecorder& rec, double before, double after) {
    const double d = after - before;
    if (d != rec.last_delta) {
      if (rec.points.back().t_s < t_s) rec.points.push_back({t_s, before});
      rec.last_delta = d;
    }
  };
  arm(st_[i].alpha, prev_[i].alpha_deg, cur_[i].alpha_deg);
  arm(st_[i].beta, prev_[i].beta_deg, cur_[i].beta_deg);
}

StepperResult Stepper::run() {
  const std::size_t n = m_.size();
  for (std::size_t ka = 0; ka < 3; ++ka) {
    const double da = (static_cast<double>(ka) - 1) * o_.alpha_step_deg;
    turn_alpha_[ka] = unit(da * kRad);
    for (std::size_t kb = 0; kb < 3; ++kb)
      turn_beta_[ka][kb] = unit((da + (static_cast<double>(kb) - 1) * o_.beta_step_deg) * kRad);
  }
  prev_.resize(n);
  for (std::size_t i = 0; i < n; ++i) prev_[i] = robots_[i].start;
  cur_ = prev_;
  seg_prev_.resize(n);
  m_.segments(prev_, seg_prev_);
  seg_cur_ = seg_prev_;
  trav_.assign(n, 0.0);
  st_.assign(n, {});
  fields_.assign(n, {});
  field_tried_.assign(n, false);
  for (std::size_t i = 0; i < n; ++i) {
    st_[i].alpha.points.push_back({0.0, prev_[i].alpha_deg});
    st_[i].beta.points.push_back({0.0, prev_[i].beta_deg});
  }
  std::vector<std::uint32_t> order, scripted;
  is_scripted_.assign(n, false);
  double script_end = 0;
  std::vector<std::pair<AngleCursor, AngleCursor>> cursors;
  for (std::size_t i = 0; i < n; ++i) {
    if (robots_[i].frozen) continue;
    if (const RobotTrajectory* sc = robots_[i].script) {
      is_scripted_[i] = true;
      scripted.push_back(static_cast<std::uint32_t>(i));
      cursors.emplace_back(AngleCursor(sc->alpha), AngleCursor(sc->beta));
      script_end = std::max({script_end, sc->alpha.back().t_s, sc->beta.back().t_s});
    } else {
      order.push_back(static_cast<std::uint32_t>(i));
    }
  }
  has_scripts_ = !scripted.empty();
  rank_.resize(n);
  std::iota(rank_.begin(), rank_.end(), 0u);
  std::shuffle(rank_.begin(), rank_.end(), rng_);
  std::vector<bool> is_first(n, false);
  for (const std::uint32_t i : o_.first)
    if (i < n && !robots_[i].frozen) is_first[i] = true;
  for (std::size_t i = 0; i < n; ++i)
    if (is_first[i]) rank_[i] += static_cast<std::uint32_t>(n);

  const auto max_steps = static_cast<std::size_t>(std::ceil(o_.max_duration_s / o_.dt_s));
  std::size_t step = 0, last_motion = 0, quiet = 0;
  const auto stall_steps = o_.stall_s > 0 ? static_cast<std::size_t>(std::ceil(o_.stall_s / o_.dt_s)) : max_steps;
  std::size_t fewest_away = n + 1, last_arrival = 0;
  for (; step < max_steps; ++step) {
    const double t = static_cast<double>(step) * o_.dt_s;
    const bool scripts_running = t < script_end;
    bool pending = scripts_running;
    std::size_t away = 0;
    for (const std::uint32_t i : order) {
      if (prev_[i] != robots_[i].goal) ++away;
      if (prev_[i] != robots_[i].goal || st_[i].escape_left > 0) pending = true;
    }
    if (!pending) break;
    if (away < fewest_away) {
      fewest_away = away;
      last_arrival = step;
    } else if (step - last_arrival > stall_steps && !scripts_running) {
      break;  // the robots left keep each other stuck
    }
    // Scripted robots take their step first: everyone planned checks against it.
    for (std::size_t k = 0; k < scripted.size(); ++k) {
      const std::uint32_t j = scripted[k];
      const double t1 = static_cast<double>(step + 1) * o_.dt_s;
      const Pose q{cursors[k].first.at(t1), cursors[k].second.at(t1)};
      cur_[j] = q;
      seg_cur_[j] = q == prev_[j] ? seg_prev_[j] : m_.robot(j).collision_segment(q);
      const Positioner& r = m_.robot(j);
      trav_[j] = (std::abs(q.alpha_deg - prev_[j].alpha_deg) * r.reach_mm() +
                  std::abs(q.beta_deg - prev_[j].beta_deg) * r.collision_length_mm()) * kRad;
    }
    std::shuffle(order.begin(), order.end(), rng_);
    if (!o_.first.empty())
      std::stable_partition(order.begin(), order.end(), [&](std::uint32_t i) { return is_first[i]; });
    for (const std::uint32_t i : order) step_robot(i);
    bool moved = false;
    for (const std::uint32_t j : scripted) {
      prev_[j] = cur_[j];
      seg_prev_[j] = seg_cur_[j];
      trav_[j] = 0;
    }
    for (const std::uint32_t i : order) {
      record(i, t);
      if (cur_[i] != prev_[i]) moved = true;
      prev_[i] = cur_[i];
      seg_prev_[i] = seg_cur_[i];
      trav_[i] = 0;
    }
    if (moved) {
      last_motion = step + 1;
      quiet = 0;
    } else if (++quiet > 400 && !scripts_running) {
      break;  // nobody can move at all any more
    }
  }

  StepperResult out;
  out.steps = step;
  out.escapes = escapes_;
  out.duration_s = static_cast<double>(last_motion) * o_.dt_s;
  out.paths.resize(n);
  out.end = prev_;
  out.reached.assign(n, false);
  out.blockers.resize(n);
  const double t_end = static_cast<double>(step) * o_.dt_s;
  for (std::size_t i = 0; i < n; ++i) {
    auto finish = [&](ArmRecorder& rec, double angle) {
      if (rec.last_delta != 0 && rec.points.back().t_s < t_end) rec.points.push_back({t_end, angle});
      return std::move(rec.points);
    };
    out.paths[i].alpha = finish(st_[i].alpha, prev_[i].alpha_deg);
    out.paths[i].beta = finish(st_[i].beta, prev_[i].beta_deg);
    out.reached[i] = robots_[i].frozen || is_scripted_[i] || prev_[i] == robots_[i].goal;
    if (!out.reached[i]) {
      // Who stands in the way of the direct move towards the goal.
      const Pose p = prev_[i], g = robots_[i].goal;
      const Move mv{std::clamp(g.alpha_deg - p.alpha_deg, -o_.alpha_step_deg, o_.alpha_step_deg),
                    std::clamp(g.beta_deg - p.beta_deg, -o_.beta_step_deg, o_.beta_step_deg)};
      const Pose q = apply(p, mv, g);
      feasible(i, q, moved_segment(i, mv, q), travel(i, mv), false, &out.blockers[i]);
    }
  }
  out.pair_checks = checks_;
  out.violations = violations_;
  return out;
}

}  // namespace

StepperResult drive_to_goals(const CollisionModel& model, std::span<const StepperRobot> robots,
                             const StepperOptions& options) {
  Stepper s(model, robots, options);
  return s.run();
}

}  // namespace axon::fps::plan
