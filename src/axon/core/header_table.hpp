// Text tables whose first line names the columns: the shape of the planner's target files and the
// measurement files of correction moves. '#' starts a comment, blank lines are skipped, cells are
// separated by commas (core::split_fields), header names match case-insensitively and may have
// aliases ("fibre" / "fiber" for one field). The reader checks the header and the cell count of
// every row and hands out cells by field number; what a cell means is the caller's business.
#pragma once

#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace axon::core {

struct TableColumn {
  std::string_view name;  // lower case
  int field;              // 0..field_count-1; aliases share a field; the first name is the one listed in errors
};

enum class TableProblem {
  unknown_column,    // a header name that is not one of the columns
  duplicate_column,  // a field named twice in the header (also through an alias)
  missing_column,    // a required field the header lacks
  cell_count,        // a row whose cell count differs from the header's
};

struct TableError {
  TableProblem problem;
  int line;             // 1-based line of the text
  std::string message;  // without the line: "unknown column 'z' (known: robot, x, y)"
};

class HeaderTable {
 public:
  // `columns` and `required` must outlive the reader; `text` too (cells are views into it).
  HeaderTable(std::string_view text, std::span<const TableColumn> columns, std::span<const int> required);

  // Moves to the next data row (reading the header on the way); false at the end of the text or
  // at the first error (then error() says which).
  bool next();

  [[nodiscard]] const std::optional<TableError>& error() const noexcept { return error_; }
  [[nodiscard]] bool header_seen() const noexcept { return !fields_of_cell_.empty(); }
  // Line of the current row (or of the last line read).
  [[nodiscard]] int line() const noexcept { return line_; }
  // Whether the header has this field.
  [[nodiscard]] bool has(int field) const noexcept;
  // The current row's cell of `field` ("" when the header has no such column).
  [[nodiscard]] std::string_view cell(int field) const noexcept;

 private:
  bool read_header(const std::vector<std::string_view>& cells);
  bool fail(TableProblem p, std::string message);

  std::string_view rest_;
  std::span<const TableColumn> columns_;
  std::span<const int> required_;
  std::vector<int> fields_of_cell_;         // header position -> field
  std::vector<std::string_view> by_field_;  // current row: field -> cell
  std::optional<TableError> error_;
  int line_ = 0;
};

}  // namespace axon::core
