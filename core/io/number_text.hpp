#pragma once
// Writing floating-point numbers as text that reads back bit for bit.

#include <string>

namespace tessera {

/// Appends `x` in the shortest decimal form that strtod reads back to exactly the same
/// double (std::to_chars round-trip form: "0.1", "10", "1e-20"). It is uniquely defined,
/// so output is byte-identical across platforms, and it is several times faster than
/// printf("%.17g") on large graphs. Non-finite values are written as "nan"/"inf"/"-inf".
void append_number(std::string& out, double x);

/// The shortest of x's 15, 16 and 17 significant-digit printf("%g") forms that strtod reads back
/// to exactly x: for numbers on a child process's command line, which parses them again.
std::string exact_text(double x);

/// Appends a non-negative integer in decimal.
void append_integer(std::string& out, unsigned long long x);

}  // namespace tessera
