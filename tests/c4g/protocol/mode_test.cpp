#include "axon/c4g/protocol/mode.hpp"

#include "axon/c4g/protocol/error.hpp"

#include <gtest/gtest.h>

#include <set>
#include <vector>

using namespace axon::c4g::protocol;

TEST(C4gMode, EveryDocumentedCodeHasANameAndOthersDoNot) {
  for (int c : {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 14, 15, 17, 170, 100, 101, 102, 103, 150, 199, 201, 202,
                500, 501, 502, 503, 504, 505, 506, 508})
    EXPECT_TRUE(is_known_mode(c)) << c;
  for (int c : {-1, 13, 16, 18, 99, 200, 203, 255, 499, 507, 509, 1000}) EXPECT_FALSE(is_known_mode(c)) << c;
  EXPECT_EQ(mode_name(0), "mode0");
  EXPECT_EQ(mode_name(10), "mode0_prime");
  EXPECT_EQ(mode_name(11), "mode1_standby");
  EXPECT_EQ(mode_name(170), "mode7_standby_exit");
  EXPECT_EQ(mode_name(150), "sensor");
  EXPECT_EQ(mode_name(102), "sensor_camera");
  EXPECT_EQ(mode_name(505), "drive_off");
  EXPECT_EQ(mode_name(508), "following_error");
  EXPECT_EQ(mode_name(507), "unknown");
}

TEST(C4gMode, NamesAndLabelsAreUniqueAndParseBack) {
  std::set<std::string_view> names, labels;
  for (const ModeInfo& m : all_modes()) {
    EXPECT_TRUE(names.insert(m.name).second) << m.name;
    EXPECT_TRUE(labels.insert(m.label).second) << m.label;
    EXPECT_FALSE(m.description.empty());
    EXPECT_EQ(parse_mode(m.name), code(m.mode));
    EXPECT_EQ(parse_mode(m.label), code(m.mode)) << m.label;
  }
  EXPECT_EQ(parse_mode("0'"), 10);
  EXPECT_EQ(parse_mode("DRIVE_OFF"), 505);
  EXPECT_EQ(parse_mode("17"), 17);
  EXPECT_EQ(parse_mode("123"), 123);
  EXPECT_EQ(parse_mode("507"), std::nullopt);
  EXPECT_EQ(parse_mode("mode10"), std::nullopt);
  EXPECT_EQ(parse_mode(""), std::nullopt);
}

TEST(C4gMode, FieldsThePcMustFill) {
  EXPECT_EQ(find_mode(0)->pc_fields, 0);
  EXPECT_EQ(find_mode(10)->pc_fields, kFieldD1 | kFieldD2);  // echo of the targets
  EXPECT_EQ(find_mode(1)->pc_fields, kFieldD1 | kFieldD2 | kFieldD4 | kFieldD5);
  EXPECT_EQ(find_mode(2)->pc_fields, kFieldD4 | kFieldD5);
  EXPECT_EQ(find_mode(4)->pc_fields, kFieldD1 | kFieldD2);
  EXPECT_EQ(find_mode(7)->pc_fields, kFieldD1);
  EXPECT_EQ(find_mode(8)->pc_fields, kFieldD4);
  EXPECT_EQ(find_mode(9)->pc_fields, kFieldD5);
  EXPECT_EQ(find_mode(101)->pc_fields, kFieldD3);
  EXPECT_EQ(find_mode(505)->origin, Origin::pc);
  EXPECT_EQ(find_mode(508)->origin, Origin::pc);
  EXPECT_EQ(find_mode(500)->origin, Origin::pc);
  EXPECT_EQ(find_mode(501)->origin, Origin::controller);
  EXPECT_FALSE(find_mode(3)->available);
  EXPECT_FALSE(find_mode(6)->available);
  EXPECT_FALSE(find_mode(201)->available);
  EXPECT_TRUE(find_mode(9)->available);
}

TEST(C4gMode, CheckModesFindsTheFirstUndefinedCode) {
  Packet p;
  p.count = 3;
  p.axes[0].mode = 4;
  p.axes[1].mode = 507;
  p.axes[2].mode = 999;
  const Fault f = check_modes(p);
  EXPECT_EQ(f.code, ProtocolErrc::unknown_mode);
  EXPECT_EQ(f.axis, 1);
  EXPECT_EQ(f.got, 507);
  p.axes[1].mode = 170;
  p.axes[2].mode = 505;
  EXPECT_TRUE(check_modes(p).ok());
}

TEST(C4gMode, ModeChangeRules) {
  EXPECT_EQ(check_mode_change(0, 4, false), ModeChange::allowed);        // from mode 0
  EXPECT_EQ(check_mode_change(4, 4, false), ModeChange::unchanged);      // unchanged
  EXPECT_EQ(check_mode_change(4, 7, false), ModeChange::not_from_mode0);  // mode to mode directly
  EXPECT_EQ(check_mode_change(4, 7, true), ModeChange::allowed);          // after exit-from-open
  EXPECT_EQ(check_mode_change(7, 505, false), ModeChange::allowed);       // drive-off from anywhere
  EXPECT_EQ(check_mode_change(1, 508, false), ModeChange::allowed);       // following error from anywhere
  EXPECT_EQ(check_mode_change(501, 1, true), ModeChange::driving_on);     // ignored while driving on
  EXPECT_EQ(check_mode_change(501, 0, false), ModeChange::driving_on);
  EXPECT_EQ(check_mode_change(0, 507, false), ModeChange::unknown_mode);
  EXPECT_EQ(check_mode_change(0, 500, false), ModeChange::allowed);       // freezing from mode 0
  EXPECT_EQ(check_mode_change(0, 14, false), ModeChange::controller_only);   // standby codes are the controller's
  EXPECT_EQ(check_mode_change(0, 502, false), ModeChange::controller_only);  // so is passive freezing
  EXPECT_EQ(check_mode_change(2, 12, false), ModeChange::allowed);         // the PC starts the end of mode 2
  EXPECT_EQ(check_mode_change(4, 500, true), ModeChange::not_from_mode0);  // ... only from mode 0
  EXPECT_TRUE(may_set_mode(2, 2, false));
  EXPECT_FALSE(may_set_mode(2, 9, false));
}

TEST(C4gMode, StandbyCodesAndExitSequences) {
  EXPECT_EQ(standby_of(1), 11);
  EXPECT_EQ(standby_of(2), 12);
  EXPECT_EQ(standby_of(4), 14);
  EXPECT_EQ(standby_of(5), 15);
  EXPECT_EQ(standby_of(7), 17);
  EXPECT_EQ(standby_of(9), std::nullopt);
  EXPECT_EQ(base_of_standby(170), 7);
  EXPECT_EQ(base_of_standby(12), 2);
  EXPECT_EQ(base_of_standby(0), std::nullopt);
  auto seq = [](int m, bool done) {
    const auto s = exit_sequence(m, done);
    return std::vector<std::int32_t>(s.view().begin(), s.view().end());
  };
  EXPECT_EQ(seq(1, true), (std::vector<std::int32_t>{11, 0}));
  EXPECT_EQ(seq(2, true), (std::vector<std::int32_t>{12, 0}));
  EXPECT_EQ(seq(7, true), (std::vector<std::int32_t>{170, 0}));
  EXPECT_EQ(seq(7, false), (std::vector<std::int32_t>{17, 170, 0}));
  EXPECT_EQ(seq(9, false), (std::vector<std::int32_t>{0}));
  EXPECT_TRUE(seq(0, true).empty());
  EXPECT_TRUE(seq(10, true).empty());
}

TEST(C4gMode, PhasesStartCruiseEnd) {
  EXPECT_TRUE(phases(1).has_cruise);
  EXPECT_TRUE(phases(2).has_cruise);
  for (int m : {0, 10, 4, 5, 7, 8, 9}) EXPECT_FALSE(phases(m).has_cruise) << m;
  EXPECT_EQ(phases(0).end_by, EndTrigger::controller_sets_mode);
  EXPECT_EQ(phases(4).end_by, EndTrigger::pc_exit_from_open);
  EXPECT_EQ(phases(1).end_by, EndTrigger::pc_exit_from_open);
  EXPECT_EQ(phases(505).end_by, EndTrigger::none);
}

TEST(C4gMode, StateMachineTransitions) {
  using S = MotionState;
  using E = MotionEvent;
  EXPECT_EQ(next_state(S::stop, E::move), S::closed);
  EXPECT_EQ(next_state(S::closed, E::motion_end), S::stop);
  EXPECT_EQ(next_state(S::stop, E::go_open_a), S::open_a);
  EXPECT_EQ(next_state(S::open_a, E::exit_from_open), S::stop);
  EXPECT_EQ(next_state(S::stop, E::go_open_b), S::open_b);
  EXPECT_EQ(next_state(S::open_b, E::exit_from_open), S::closed);
  EXPECT_EQ(next_state(S::open_b, E::motion_end), S::open_a);
  // Not allowed: every mode change passes through the still state.
  EXPECT_EQ(next_state(S::closed, E::go_open_b), std::nullopt);
  EXPECT_EQ(next_state(S::closed, E::go_open_a), std::nullopt);
  EXPECT_EQ(next_state(S::open_a, E::go_open_b), std::nullopt);
  EXPECT_EQ(next_state(S::open_a, E::move), std::nullopt);
  EXPECT_EQ(next_state(S::closed, E::exit_from_open), std::nullopt);
  EXPECT_EQ(to_string(S::open_b), "open_b");
}

TEST(C4gMode, AReplyMayCarryDataOnlyInTheFieldsItsModeUses) {
  Packet p;
  p.count = 3;
  p.axes[0].mode = code(Mode::mode4);
  p.axes[0].d1 = 1.5f;  // target position and velocity: mode 4's fields
  p.axes[0].d2 = 0.01f;
  p.axes[1].mode = code(Mode::mode9);
  p.axes[1].d5 = 2.0f;  // current contribution
  p.axes[2].mode = code(Mode::drive_off);
  EXPECT_TRUE(check_reply_fields(p).ok());
  EXPECT_EQ(nonzero_fields(p.axes[0]), kFieldD1 | kFieldD2);

  p.axes[1].d4 = 0.1f;  // a velocity contribution in mode 9
  auto f = check_reply_fields(p);
  EXPECT_EQ(f.code, ProtocolErrc::field_not_null);
  EXPECT_EQ(f.axis, 1);
  EXPECT_EQ(f.field, 4);
  EXPECT_EQ(f.got, 9);
  p.axes[1].d4 = 0;
  p.axes[2].ext1 = 1.0f;  // a special code carries no data
  f = check_reply_fields(p);
  EXPECT_EQ(f.axis, 2);
  EXPECT_EQ(f.field, 6);
}
