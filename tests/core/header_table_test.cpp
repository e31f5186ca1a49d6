// HeaderTable: the header-first text tables of target and measurement files.
#include "axon/core/header_table.hpp"

#include <gtest/gtest.h>

namespace axon::core {
namespace {

enum Field { id, value, note };
constexpr TableColumn kColumns[] = {{"id", id}, {"value", value}, {"note", note}, {"comment", note}};
constexpr int kRequired[] = {id, value};

TEST(HeaderTable, CellsByFieldInAnyColumnOrderWithCommentsAndBlankLines) {
  HeaderTable t("# a file\n\nVALUE, Id ,comment\n1.5,7,first  # trailing\n\n2.5, 8 ,\n", kColumns, kRequired);
  ASSERT_TRUE(t.next());
  EXPECT_EQ(t.line(), 4);
  EXPECT_EQ(t.cell(id), "7");
  EXPECT_EQ(t.cell(value), "1.5");
  EXPECT_EQ(t.cell(note), "first");
  EXPECT_TRUE(t.has(note));
  ASSERT_TRUE(t.next());
  EXPECT_EQ(t.line(), 6);
  EXPECT_EQ(t.cell(id), "8");
  EXPECT_EQ(t.cell(note), "");
  EXPECT_FALSE(t.next());
  EXPECT_FALSE(t.error().has_value());
  EXPECT_TRUE(t.header_seen());
}

TEST(HeaderTable, AbsentOptionalColumnGivesEmptyCells) {
  HeaderTable t("id,value\n1,2\n", kColumns, kRequired);
  ASSERT_TRUE(t.next());
  EXPECT_FALSE(t.has(note));
  EXPECT_EQ(t.cell(note), "");
  EXPECT_EQ(t.cell(99), "");
}

TEST(HeaderTable, HeaderAndRowProblemsAreTypedWithTheirLine) {
  struct Case {
    const char* text;
    TableProblem problem;
    int line;
    const char* message;
  };
  const Case cases[] = {
      {"id,value,colour\n", TableProblem::unknown_column, 1, "unknown column 'colour' (known: id, value, note)"},
      {"id,value,note,comment\n", TableProblem::duplicate_column, 1, "column 'comment' twice"},
      {"# x\nid,note\n1,a\n", TableProblem::missing_column, 2, "the header needs a 'value' column"},
      {"id,value\n1,2\n3\n", TableProblem::cell_count, 3, "1 cells, the header has 2"},
  };
  for (const auto& c : cases) {
    HeaderTable t(c.text, kColumns, kRequired);
    while (t.next()) {
    }
    ASSERT_TRUE(t.error().has_value()) << c.text;
    EXPECT_EQ(t.error()->problem, c.problem) << c.text;
    EXPECT_EQ(t.error()->line, c.line) << c.text;
    EXPECT_EQ(t.error()->message, c.message) << c.text;
    EXPECT_FALSE(t.next()) << "an error ends the table";
  }
}

TEST(HeaderTable, EmptyTextHasNoHeaderAndNoError) {
  HeaderTable t("# only a comment\n\n", kColumns, kRequired);
  EXPECT_FALSE(t.next());
  EXPECT_FALSE(t.error().has_value());
  EXPECT_FALSE(t.header_seen());
}

}  // namespace
}  // namespace axon::core
