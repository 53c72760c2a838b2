// Errors thrown by libsamp. Library code never aborts the process: bad input
// raises samp::Error with a message that names the file or field; tools catch
// it at main, print one line and exit non-zero.
#pragma once

#include <sstream>
#include <stdexcept>
#include <string>

namespace samp {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

namespace internal {
// Builds the message lazily so that a passing check costs nothing.
class ErrorBuilder {
 public:
  ErrorBuilder(const char* file, int line, const char* condition) {
    (void)file;
    (void)line;
    if (condition != nullptr && condition[0] != '\0') {
      condition_ = condition;
    }
  }
  template <typename T>
  ErrorBuilder& operator<<(const T& value) {
    stream_ << value;
    return *this;
  }
  [[noreturn]] void Throw() const {
    std::string message = stream_.str();
    if (message.empty()) message = "check failed: " + condition_;
    throw Error(message);
  }

 private:
  std::ostringstream stream_;
  std::string condition_;
};
struct ErrorThrower {
  [[noreturn]] void operator&(const ErrorBuilder& builder) const { builder.Throw(); }
};
}  // namespace internal

}  // namespace samp

// SAMP_CHECK(cond) << "message " << value;  throws samp::Error when cond is false.
#define SAMP_CHECK(condition)                   \
  if (condition) {                              \
  } else                                        \
    ::samp::internal::ErrorThrower() &          \
        ::samp::internal::ErrorBuilder(__FILE__, __LINE__, #condition)

// SAMP_THROW() << "message";  always throws samp::Error.
#define SAMP_THROW() \
  ::samp::internal::ErrorThrower() & ::samp::internal::ErrorBuilder(__FILE__, __LINE__, "")
