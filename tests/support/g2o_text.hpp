#pragma once
// Reading g2o text written by a test, and the check that bad text is refused with a message
// naming file, line and problem: shared by the reader's tests and the robot-key tests.

#include <string>
#include <tessera/io/g2o_reader.hpp>

namespace tessera::test {

/// Reads `text` as if it were the file "t.g2o".
G2oReadResult read_test_g2o(const std::string& text, const G2oReadOptions& options = {});

/// Reading `text` (as "t.g2o") must throw an InputError whose message starts with `where`
/// (e.g. "t.g2o:3: ") and contains `problem`.
void expect_g2o_error(const std::string& text, const std::string& where, const std::string& problem,
                      const G2oReadOptions& options = {});

}  // namespace tessera::test
