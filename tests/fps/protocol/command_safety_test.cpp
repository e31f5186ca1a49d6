// The command table's safety class (commands.hpp, "Motion and the collision lock"): every command
// of the table is classified as decided from the interface document, none is both moving and
// read-only, and a new command cannot enter the table without a class chosen here.
#include "axon/fps/protocol/commands.hpp"

#include <gtest/gtest.h>

#include <map>
#include <string_view>

using namespace axon::fps::protocol;

namespace {

enum class Class { moves, read_only, stops, setting, from_device };

// The decision, command by command (document sections in commands.hpp and docs/fps-protocol.md).
const std::map<int, Class> kExpected{
    {1, Class::read_only},   {2, Class::read_only},   {3, Class::read_only},   {10, Class::moves},
    {11, Class::moves},      {12, Class::moves},      {13, Class::stops},      {14, Class::moves},
    {15, Class::stops},      {18, Class::from_device}, {20, Class::moves},     {21, Class::moves},
    {22, Class::moves},      {23, Class::moves},      {24, Class::moves},      {25, Class::moves},
    {26, Class::moves},      {27, Class::moves},      {28, Class::moves},      {29, Class::read_only},
    {30, Class::moves},      {31, Class::moves},      {32, Class::read_only},  {33, Class::setting},
    {34, Class::read_only},  {35, Class::setting},    {40, Class::setting},    {41, Class::setting},
    {44, Class::read_only},  {45, Class::read_only},  {47, Class::moves},      {48, Class::moves},
    {49, Class::moves},      {53, Class::setting},    {54, Class::read_only},  {55, Class::read_only},
    {56, Class::read_only},  {57, Class::read_only},  {58, Class::read_only},  {59, Class::read_only},
    {106, Class::read_only}, {107, Class::read_only}, {108, Class::read_only}, {110, Class::read_only},
    {111, Class::setting},   {112, Class::setting},   {113, Class::read_only}, {116, Class::setting},
    {117, Class::setting},   {118, Class::setting},   {119, Class::setting},   {120, Class::setting},
    {121, Class::setting},   {122, Class::setting},   {123, Class::setting},   {124, Class::setting},
    {125, Class::setting},   {126, Class::setting},   {127, Class::setting},   {128, Class::setting},
    {129, Class::setting},   {130, Class::setting},   {131, Class::setting},   {132, Class::read_only},
    {200, Class::setting},   {201, Class::setting},
};

bool starts_with(std::string_view s, std::string_view p) { return s.substr(0, p.size()) == p; }

}  // namespace

TEST(FpsCommandSafety, EveryCommandOfTheTableHasItsDecidedClass) {
  EXPECT_EQ(kExpected.size(), kCommands.size());
  for (const auto& c : kCommands) {
    const auto it = kExpected.find(c.number());
    ASSERT_NE(it, kExpected.end()) << c.name << " has no class decided in this test";
    const Class want = it->second;
    EXPECT_EQ(c.moves, want == Class::moves) << c.name;
    EXPECT_EQ(c.read_only, want == Class::read_only) << c.name;
    EXPECT_EQ(c.host_sends, want != Class::from_device) << c.name;
  }
}

TEST(FpsCommandSafety, NoCommandBothMovesAndOnlyReads) {
  for (const auto& c : kCommands) EXPECT_FALSE(c.moves && c.read_only) << c.name;
}

TEST(FpsCommandSafety, TheNamesAgreeWithTheFlags) {
  // Every GET_* only reads and nothing else does; every go-to and calibration moves.
  for (const auto& c : kCommands) {
    EXPECT_EQ(c.read_only, starts_with(c.name, "GET_")) << c.name;
    if (starts_with(c.name, "GO_TO_") || starts_with(c.name, "CALIBRATE_")) {
      EXPECT_TRUE(c.moves) << c.name;
    }
  }
}

TEST(FpsCommandSafety, TheStopsAndTheUnlockCommandNeverMove) {
  // TRAJECTORY_ABORT stops everything, STOP_TRAJECTORY also clears the collision flags (unlock).
  for (auto id : {CommandId::trajectory_abort, CommandId::stop_trajectory}) {
    EXPECT_FALSE(command_info(id).moves) << command_name(id);
    EXPECT_FALSE(command_info(id).read_only) << command_name(id);
  }
}
