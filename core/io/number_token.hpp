#pragma once
// Reading one token of a text file (a run of non-blank bytes) as a number, exactly as strtod
// would but without its locale and copying, and quoting a token in an error message. The
// reading counterpart of number_text.hpp.

#include <string>
#include <string_view>

namespace tessera {

/// Parses the whole token as a double: true and `out` set, correctly rounded, when it is a
/// decimal number (sign, digits, optional point and exponent; a leading '+' is accepted, as
/// strtod would) or inf/nan; false when any byte does not belong to one. `out` may be inf
/// or nan when the token says so or overflows (the caller decides whether that is allowed);
/// an underflow gives what strtod gives (a subnormal value or 0).
bool parse_number(std::string_view token, double& out);

/// The token in single quotes for a message: at most its first 40 bytes (then "..."),
/// non-printable bytes written as \xNN, so a binary file cannot garble the terminal.
std::string quoted_token(std::string_view token);

}  // namespace tessera
