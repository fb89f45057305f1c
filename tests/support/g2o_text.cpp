#include "g2o_text.hpp"

#include <gtest/gtest.h>

#include <tessera/util/input_error.hpp>

namespace tessera::test {

G2oReadResult read_test_g2o(const std::string& text, const G2oReadOptions& options) {
  return read_g2o_text(text, "t.g2o", options);
}

void expect_g2o_error(const std::string& text, const std::string& where, const std::string& problem,
                      const G2oReadOptions& options) {
  try {
    read_test_g2o(text, options);
    ADD_FAILURE() << "no error for input:\n" << text;
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_EQ(msg.rfind(where, 0), 0u) << "message: " << msg;
    EXPECT_NE(msg.find(problem), std::string::npos) << "message: " << msg;
  }
}

}  // namespace tessera::test
