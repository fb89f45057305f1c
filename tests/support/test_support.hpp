#pragma once
// Helpers shared by the tests: where ../shared lives, temporary files, running binaries.

#include <gtest/gtest.h>

#include <string>
#include <tessera/util/input_error.hpp>

namespace tessera::test {

/// The shared data folder (datasets/, reference/) configured at build time, or "" when it
/// does not exist on this machine.
std::string shared_dir();

/// A fresh temporary directory for this test (/tmp/tessera_test_<Suite>_<Test>_<random>),
/// removed when the test passes, kept when it fails (TESSERA_KEEP_TEST_DIRS=1 keeps them all).
/// Made inside a test, it lives only as long as that test: never cache it across tests.
std::string temp_dir();

/// Writes `text` into `dir/name` and returns the path.
std::string write_file(const std::string& dir, const std::string& name, const std::string& text);

/// The whole text of the file at `path` ("" when it cannot be read).
std::string read_text_file(const std::string& path);

/// Whether `part` occurs in `text`: for checking printed output and written files.
bool contains(const std::string& text, const std::string& part);

/// Runs a shell command, returns its exit code and captures stdout+stderr into `output`.
int run_command(const std::string& command, std::string* output);

/// Path of a built executable (build/bin/NAME).
std::string bin(const std::string& name);

/// What `f()` throws as InputError, or "" when it throws nothing: for the "bad input says what
/// is wrong" tests.
template <class F>
std::string input_error_of(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

/// What `options.validate()` throws as InputError, or "" when the options are valid: for the
/// "bad options name the field" tests.
template <class Options>
std::string validation_message(const Options& options) {
  return input_error_of([&options] { options.validate(); });
}

/// Whether `options.validate()` throws an InputError whose message contains `field` (a field's
/// name, often qualified: "RobustOptions.mu_step"); a failure shows what it threw instead, or
/// that it accepted the options. For `EXPECT_TRUE(test::validation_names(o, "..."))`.
template <class Options>
::testing::AssertionResult validation_names(const Options& options, const std::string& field) {
  const std::string message = validation_message(options);
  if (message.find(field) != std::string::npos) return ::testing::AssertionSuccess();
  if (message.empty())
    return ::testing::AssertionFailure()
           << "validate() accepted the options, expected an error naming '" << field << "'";
  return ::testing::AssertionFailure()
         << "validate() threw '" << message << "', which does not name '" << field << "'";
}

}  // namespace tessera::test

/// Skips the current test with a clear message when ../shared is not there.
#define TESSERA_REQUIRE_SHARED()                                                          \
  do {                                                                                    \
    if (tessera::test::shared_dir().empty())                                              \
      GTEST_SKIP() << "../shared (datasets and reference optima) is missing next to the " \
                      "checkout: skipping this dataset test";                             \
  } while (0)
