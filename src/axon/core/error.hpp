// Errors: one result type for expected failures, one exception type for API boundaries.
//
// Every layer has its own error-code enum registered as a std::error_category; the category's
// messages say what went wrong and what to do about it. An Error carries such a code plus a
// detail string with the context (which file, which bus, which byte).
#pragma once

#include <boost/outcome/result.hpp>
#include <boost/outcome/try.hpp>

#include <stdexcept>
#include <string>
#include <system_error>
#include <utility>

namespace axon {

namespace outcome = BOOST_OUTCOME_V2_NAMESPACE;

struct Error {
  std::error_code code;
  std::string detail;  // context: what was being done, with which input

  Error() = default;
  Error(std::error_code c, std::string d = {}) : code(c), detail(std::move(d)) {}

  // "detail: code message" (or just the code message when there is no detail).
  [[nodiscard]] std::string message() const;
  friend bool operator==(const Error& e, std::error_code c) { return e.code == c; }
  template <class E>
    requires std::is_error_code_enum_v<E>
  friend bool operator==(const Error& e, E c) {
    return e.code == std::error_code(c);
  }
};

// Thrown at API boundaries (CLI, constructors that validate); carries the Error.
class Exception : public std::runtime_error {
 public:
  explicit Exception(Error e) : std::runtime_error(e.message()), error_(std::move(e)) {}
  [[nodiscard]] const Error& error() const noexcept { return error_; }
  [[nodiscard]] std::error_code code() const noexcept { return error_.code; }

 private:
  Error error_;
};

// Accessing the value of a failed Result throws axon::Exception with its Error.
struct ThrowErrorPolicy : outcome::policy::base {
  template <class Impl>
  static constexpr void wide_value_check(Impl&& self) {
    if (!base::_has_value(std::forward<Impl>(self))) {
      if (base::_has_error(std::forward<Impl>(self))) throw Exception(base::_error(std::forward<Impl>(self)));
      throw std::logic_error("axon::Result has neither value nor error");
    }
  }
  template <class Impl>
  static constexpr void wide_error_check(Impl&& self) {
    if (!base::_has_error(std::forward<Impl>(self))) throw std::logic_error("axon::Result has no error");
  }
};

template <class T>
using Result = outcome::result<T, Error, ThrowErrorPolicy>;

inline auto ok() { return outcome::success(); }

template <class E>
  requires std::is_error_code_enum_v<E>
inline Error make_error(E code, std::string detail = {}) {
  return Error(std::error_code(code), std::move(detail));
}

// Unwraps a Result at an API boundary: returns the value or throws axon::Exception.
template <class T>
decltype(auto) value_or_throw(Result<T>&& r) {
  return std::move(r).value();
}

// Errors of the core layer (configuration, system calls, time).
enum class CoreErrc {
  invalid_argument = 1,
  config_syntax,
  config_missing_key,
  config_bad_value,
  config_unknown_key,
  io,
  timeout,
  cancelled,
  closed,
  not_supported,
  permission,
};
const std::error_category& core_category() noexcept;
inline std::error_code make_error_code(CoreErrc e) noexcept { return {static_cast<int>(e), core_category()}; }

}  // namespace axon

template <>
struct std::is_error_code_enum<axon::CoreErrc> : std::true_type {};

// AXON_TRY(name, expr): evaluates expr (a Result); on error returns the error from the enclosing
// function, else binds the value to `auto&& name`. AXON_TRY(expr) for Result<void>.
// AXON_CO_TRY does the same inside a coroutine (co_return).
#define AXON_TRY BOOST_OUTCOME_TRY
#define AXON_CO_TRY BOOST_OUTCOME_CO_TRY
