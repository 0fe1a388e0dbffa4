// Error handling shared by every layer of ident.
//
// Provides:
//   ident::InvalidArgument   thrown when a caller breaks a documented precondition (bad sizes, NaN,
//                            non-positive-definite matrices, invalid options). Derives from
//                            std::invalid_argument; what() is one line that names the argument.
//   ident::DataError         thrown by readers when a file or record is unusable (names file/line/column).
//   IDENT_REQUIRE(cond, fmt, args...)   always-on precondition check that throws InvalidArgument.
//
// Example:
//   IDENT_REQUIRE(options.forgetting > 0 && options.forgetting <= 1,
//                 "forgetting = {}; need 0 < forgetting <= 1", options.forgetting);
#pragma once

#include <stdexcept>
#include <string>
#include <utility>

#include <fmt/core.h>

namespace ident {

class InvalidArgument : public std::invalid_argument {
 public:
  explicit InvalidArgument(const std::string& what) : std::invalid_argument(what) {}
};

class DataError : public std::runtime_error {
 public:
  explicit DataError(const std::string& what) : std::runtime_error(what) {}
};

namespace internal {
[[noreturn, gnu::cold, gnu::noinline]] inline void ThrowInvalidArgument(const std::string& message) {
  throw InvalidArgument(message);
}
}  // namespace internal

}  // namespace ident

#define IDENT_REQUIRE(condition, ...)                                    \
  do {                                                                   \
    if (!(condition)) [[unlikely]] {                                     \
      ::ident::internal::ThrowInvalidArgument(fmt::format(__VA_ARGS__)); \
    }                                                                    \
  } while (false)
