#include "axon/core/progress.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <string>

namespace {

using namespace std::chrono_literals;
using axon::core::ManualClock;
using axon::core::Progress;
using axon::core::ProgressOptions;

std::string contents(std::FILE* f) {
  std::fflush(f);
  std::rewind(f);
  std::string s;
  for (int c; (c = std::fgetc(f)) != EOF;) s += static_cast<char>(c);
  return s;
}

ProgressOptions opts(int terminal) {
  ProgressOptions o;
  o.terminal = terminal;
  return o;
}

TEST(Progress, IntoAFileWritesPlainLinesAtMostOncePerIntervalAfterTheQuietTime) {
  std::FILE* f = std::tmpfile();
  ManualClock clock;
  {
    Progress p(f, opts(0), clock);
    EXPECT_FALSE(p.update("0.5 s"));  // work that ends within 2 s prints nothing but its result
    clock.advance(2s);
    EXPECT_TRUE(p.update("2.0 s"));
    clock.advance(500ms);
    EXPECT_FALSE(p.update("2.5 s"));
    clock.advance(500ms);
    EXPECT_TRUE(p.update("3.0 s"));
    EXPECT_EQ(p.reports(), 2);
  }
  EXPECT_EQ(contents(f), "2.0 s\n3.0 s\n");  // no carriage return in a log
  std::fclose(f);
}

TEST(Progress, OnATerminalRewritesOneLineAndEndsIt) {
  std::FILE* f = std::tmpfile();
  ManualClock clock;
  {
    Progress p(f, opts(1), clock);
    clock.advance(2s);
    p.update("moving: 10 of 500");
    clock.advance(1s);
    p.update("moving: 9");
  }
  // The shorter second text blanks the rest of the first; the destructor ends the line.
  EXPECT_EQ(contents(f), "\rmoving: 10 of 500\rmoving: 9        \n");
  std::fclose(f);
}

TEST(Progress, NothingWrittenLeavesNothingToEnd) {
  std::FILE* f = std::tmpfile();
  ManualClock clock;
  { Progress p(f, opts(1), clock); }
  EXPECT_EQ(contents(f), "");
  std::fclose(f);
}

}  // namespace
