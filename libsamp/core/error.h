// Errors thrown by libsamp. Library code never aborts the process: bad input
// raises samp::Error with a message that names the file or field; tools catch
// it at main, print one line and exit non-zero. In debug builds (NDEBUG not
// defined) the messages of SAMP_CHECK and SAMP_THROW end with the source file
// and line that threw, e.g. " [fitter.cc:207]"; release builds leave them out.
#pragma once

#include <cstring>
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
  ErrorBuilder(const char* file, int line, const char* condition) : file_(file), line_(line) {
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
#ifndef NDEBUG
    // Debug builds say where: " [fitter.cc:207]" (the source file's name and line).
    const char* slash = std::strrchr(file_, '/');
    message += " [" + std::string(slash != nullptr ? slash + 1 : file_) + ":" + std::to_string(line_) + "]";
#endif
    throw Error(message);
  }

 private:
  std::ostringstream stream_;
  std::string condition_;
  // Used in debug builds only (Throw above).
  [[maybe_unused]] const char* file_;
  [[maybe_unused]] int line_;
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
