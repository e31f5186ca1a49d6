// JSON written by hand where the shape is fixed and large (500 robots ten times a second): the
// one helper that must be right, a quoted and escaped string.
#pragma once

#include <string>
#include <string_view>

namespace axon::web {

// "text" with quotes, backslashes and control characters escaped.
[[nodiscard]] std::string json_quote(std::string_view text);

}  // namespace axon::web
