// Checks of the samp::Error a call throws, shared by the tests of every layer.
#pragma once

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "libsamp/core/error.h"

namespace samp::test {

// The message of the samp::Error `f()` throws; a test failure and "" when it
// throws none.
template <typename F>
std::string ErrorOf(F f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "no samp::Error thrown";
  return "";
}

// Expects `f()` to throw a samp::Error whose message contains every one of `parts`.
template <typename F>
void ExpectError(F f, const std::vector<std::string>& parts) {
  const std::string message = ErrorOf(f);
  for (const std::string& part : parts) {
    EXPECT_NE(message.find(part), std::string::npos) << "'" << part << "' not in: " << message;
  }
}

}  // namespace samp::test
