#include "axon/core/header_table.hpp"

#include "axon/core/text.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>

namespace axon::core {

namespace {

bool same_name(std::string_view header, std::string_view lower_name) noexcept {
  return header.size() == lower_name.size() &&
         std::equal(header.begin(), header.end(), lower_name.begin(),
                    [](char a, char b) { return std::tolower(static_cast<unsigned char>(a)) == b; });
}

}  // namespace

HeaderTable::HeaderTable(std::string_view text, std::span<const TableColumn> columns, std::span<const int> required)
    : rest_(text), columns_(columns), required_(required) {
  int count = 0;
  for (const auto& c : columns_) count = std::max(count, c.field + 1);
  by_field_.resize(static_cast<std::size_t>(count));
}

bool HeaderTable::fail(TableProblem p, std::string message) {
  error_ = TableError{p, line_, std::move(message)};
  return false;
}

bool HeaderTable::has(int field) const noexcept {
  return std::find(fields_of_cell_.begin(), fields_of_cell_.end(), field) != fields_of_cell_.end();
}

std::string_view HeaderTable::cell(int field) const noexcept {
  if (field < 0 || static_cast<std::size_t>(field) >= by_field_.size()) return {};
  return by_field_[static_cast<std::size_t>(field)];
}

bool HeaderTable::read_header(const std::vector<std::string_view>& cells) {
  std::vector<bool> seen(by_field_.size(), false);
  for (const auto c : cells) {
    const auto it = std::find_if(columns_.begin(), columns_.end(), [&](const TableColumn& k) { return same_name(c, k.name); });
    if (it == columns_.end()) {
      std::string known;
      std::vector<bool> listed(by_field_.size(), false);
      for (const auto& k : columns_) {
        if (listed[static_cast<std::size_t>(k.field)]) continue;
        listed[static_cast<std::size_t>(k.field)] = true;
        known += known.empty() ? "" : ", ";
        known += k.name;
      }
      return fail(TableProblem::unknown_column, fmt::format("unknown column '{}' (known: {})", c, known));
    }
    const auto f = static_cast<std::size_t>(it->field);
    if (seen[f]) return fail(TableProblem::duplicate_column, fmt::format("column '{}' twice", c));
    seen[f] = true;
    fields_of_cell_.push_back(it->field);
  }
  for (const int f : required_) {
    if (seen[static_cast<std::size_t>(f)]) continue;
    const auto it = std::find_if(columns_.begin(), columns_.end(), [&](const TableColumn& k) { return k.field == f; });
    fields_of_cell_.clear();
    return fail(TableProblem::missing_column,
                fmt::format("the header needs a '{}' column", it == columns_.end() ? std::string_view("?") : it->name));
  }
  return true;
}

bool HeaderTable::next() {
  if (error_) return false;
  while (!rest_.empty()) {
    const auto nl = rest_.find('\n');
    std::string_view line = rest_.substr(0, nl);
    rest_.remove_prefix(nl == std::string_view::npos ? rest_.size() : nl + 1);
    ++line_;
    if (const auto hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
    line = trim(line);
    if (line.empty()) continue;
    const auto cells = split_fields(line);
    if (!header_seen()) {
      if (!read_header(cells)) return false;
      continue;
    }
    if (cells.size() != fields_of_cell_.size())
      return fail(TableProblem::cell_count, fmt::format("{} cells, the header has {}", cells.size(), fields_of_cell_.size()));
    std::fill(by_field_.begin(), by_field_.end(), std::string_view{});
    for (std::size_t i = 0; i < cells.size(); ++i) by_field_[static_cast<std::size_t>(fields_of_cell_[i])] = cells[i];
    return true;
  }
  return false;
}

}  // namespace axon::core
