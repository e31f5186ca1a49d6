// Smoothing of finished plans: fewer points on the arms the lock-step engine left jagged.
//
// A robot stuck in the engine for a while dithers (an escape of a degree or two, back, again) and
// moves stop-and-go, and every change of speed is a point the firmware has to store. Shortcuts
// remove them: a run of points of one arm is replaced by a straight segment in (time, angle)
// between two of its points. Such a segment never moves faster than the arm did between the same
// two points on average, so the speed limits hold; start, end and timing of the move stay.
//
// The neighbours were planned against the robot's dithering positions, so every shortcut is
// certified before it is taken, against the *current* trajectories of the robot's neighbours and
// its obstacles over the interval it changes. Conservative advancement (moving_segment.hpp): a
// point of a collision segment moves at most (alpha speed * reach + beta speed * collision length)
// (radians, mm), so with clearance c at time t and the pair's bounds summing to V over the stretch
// where both keep their speeds, the clearance stays at least m until t + (c - m) / V or the
// stretch's end; the next evaluation is there. The certificate has no sampling gap; the checker
// still verifies the whole plan afterwards.
#pragma once

#include "axon/fps/plan/collision.hpp"
#include "axon/fps/plan/trajectory.hpp"

#include <cstddef>
#include <span>
#include <vector>

namespace axon::fps::plan {

struct SmoothOptions {
  std::size_t min_points = 40;     // only arms with more points than this (after the start point)
  double min_clearance_mm = 1e-4;  // every shortcut keeps at least this much clearance throughout
  double min_step_s = 1e-4;        // a shortcut whose certificate needs smaller steps is refused
  int sweeps = 2;                  // passes over the arms still over min_points (a later pass sees
                                   // the neighbours' shortened arms)
};

struct SmoothStats {
  std::size_t arms = 0;           // arms shortened (per sweep)
  std::size_t points_before = 0;  // over those arms
  std::size_t points_after = 0;
  std::size_t shortcuts_tried = 0;
};

// Shortens every arm with more than `min_points` points (the arms with the most points first; the
// alpha arm of a robot before its beta arm), greedily: from each kept point, the farthest later
// point whose shortcut is certified (doubling, then bisection) becomes the next kept point.
// `trajectories`: one per robot in model order, times from a common origin; robots that do not
// move hold one point. `changed[i]` is set for every robot whose trajectory changed (resized).
SmoothStats smooth_arms(const CollisionModel& model, std::vector<RobotTrajectory>& trajectories,
                        const SmoothOptions& options, std::vector<bool>& changed);

}  // namespace axon::fps::plan
