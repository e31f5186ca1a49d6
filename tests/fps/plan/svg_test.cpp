// The SVG plot: well-formed XML with the expected elements.
#include "axon/fps/plan/svg.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace axon::fps::plan {
namespace {

// A minimal XML structure check: every tag closes in order, attributes are quoted, one root.
// Returns an empty string when fine, else what is wrong.
std::string check_xml(const std::string& s, std::vector<std::string>& seen) {
  std::vector<std::string> stack;
  std::size_t i = 0;
  int roots = 0;
  while ((i = s.find('<', i)) != std::string::npos) {
    const std::size_t end = s.find('>', i);
    if (end == std::string::npos) return "unterminated tag";
    std::string tag = s.substr(i + 1, end - i - 1);
    i = end + 1;
    if (tag.starts_with("?")) continue;  // XML declaration
    const std::size_t quotes = static_cast<std::size_t>(std::count(tag.begin(), tag.end(), '"'));
    if (quotes % 2 != 0) return "odd quotes in <" + tag + ">";
    if (tag.starts_with("/")) {
      if (stack.empty() || stack.back() != tag.substr(1)) return "mismatched </" + tag.substr(1) + ">";
      stack.pop_back();
      continue;
    }
    const bool self_closing = tag.ends_with("/");
    const std::string name = tag.substr(0, tag.find_first_of(" /"));
    seen.push_back(name);
    if (stack.empty()) ++roots;
    if (!self_closing) stack.push_back(name);
  }
  if (!stack.empty()) return "unclosed <" + stack.back() + ">";
  if (roots != 1) return "expected one root element";
  return {};
}

TEST(PlanSvg, WellFormedWithRobotsObstaclesPathsAndContacts) {
  std::vector<RobotSpec> r{{1, {0, 0}, {}, {}, 2.0}, {2, {48, 0}, {}, {}, 2.0}};
  std::vector<FiducialSpec> f{{9, {24, 20}, 3.0}};
  std::vector<ObstacleSpec> o{{"gfa <1>", {{-30, -30}, {-30, 30}}, 3.0}};
  const auto m = CollisionModel::build(r, ArmDesign{}, f, o).value();
  const std::vector<Pose> poses{{0, 0}, {180, 0}};  // head-on: one contact
  std::vector<Segment> segs(2);
  m.segments(poses, segs);
  std::vector<Contact> contacts;
  m.find_contacts(segs, contacts);
  ASSERT_EQ(contacts.size(), 1u);
  const std::vector<RobotTrajectory> traj{RobotTrajectory::linear({0, 180}, {0, 0}, 0, 10),
                                          RobotTrajectory::hold({180, 0})};
  const auto paths = fibre_paths(m, traj, kBossFibre, 0.5);
  ASSERT_EQ(paths.size(), 1u);  // only robot 1 moves
  EXPECT_EQ(paths[0].points.size(), 21u);
  SvgOptions opt;
  opt.title = "a & b";
  opt.patrol = true;
  const std::string svg = render_svg(m, poses, opt, paths, contacts);
  std::vector<std::string> seen;
  EXPECT_EQ(check_xml(svg, seen), "");
  EXPECT_TRUE(svg.starts_with("<?xml"));
  EXPECT_NE(svg.find("<svg xmlns=\"http://www.w3.org/2000/svg\""), std::string::npos);
  EXPECT_EQ(std::count(seen.begin(), seen.end(), "line"), 4);  // two arms per robot
  EXPECT_EQ(std::count(seen.begin(), seen.end(), "polyline"), 1);
  EXPECT_EQ(std::count(seen.begin(), seen.end(), "text"), 2);
  EXPECT_NE(svg.find("<title>a &amp; b</title>"), std::string::npos);
  EXPECT_NE(svg.find("id=\"contacts\""), std::string::npos);
  // Without buffers, paths or contacts those groups are absent.
  opt.buffers = false;
  const std::string plain = render_svg(m, poses, opt);
  seen.clear();
  EXPECT_EQ(check_xml(plain, seen), "");
  EXPECT_EQ(plain.find("id=\"buffers\""), std::string::npos);
  EXPECT_EQ(plain.find("id=\"contacts\""), std::string::npos);
  EXPECT_EQ(plain.find("polyline"), std::string::npos);
}

}  // namespace
}  // namespace axon::fps::plan
