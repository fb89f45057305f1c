#include "io/number_token.hpp"

#include <charconv>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <system_error>

namespace tessera {
namespace {

// Clinger's fast path: a plain decimal with at most 19 digits whose digit string is below
// 2^53 and whose decimal exponent is within +-22 is one exact integer times or divided by
// one exact power of ten, so a single IEEE operation rounds it correctly. Returns false
// for anything else (then the general parser decides). Most numbers in g2o files qualify.
bool parse_simple_decimal(const char* b, const char* e, double& out) {
  static constexpr double kPow10[] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                      1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                                      1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};
  const bool negative = b != e && *b == '-';
  if (negative) ++b;
  std::uint64_t mantissa = 0;
  int digits = 0, exponent = 0;
  for (; b != e && static_cast<unsigned>(*b - '0') < 10; ++b, ++digits)
    mantissa = mantissa * 10 + static_cast<unsigned>(*b - '0');
  if (b != e && *b == '.')
    for (++b; b != e && static_cast<unsigned>(*b - '0') < 10; ++b, ++digits, --exponent)
      mantissa = mantissa * 10 + static_cast<unsigned>(*b - '0');
  if (digits == 0 || digits > 19) return false;  // (more digits may have wrapped around)
  if (b != e && (*b == 'e' || *b == 'E')) {
    ++b;
    const bool exp_negative = b != e && *b == '-';
    if (b != e && (*b == '-' || *b == '+')) ++b;
    if (b == e) return false;
    int value = 0;
    for (; b != e && static_cast<unsigned>(*b - '0') < 10; ++b)
      if (value < 10000) value = value * 10 + (*b - '0');
    exponent += exp_negative ? -value : value;
  }
  if (b != e || mantissa > (std::uint64_t{1} << 53) || exponent < -22 || exponent > 22)
    return false;
  double v = static_cast<double>(mantissa);
  v = exponent < 0 ? v / kPow10[-exponent] : v * kPow10[exponent];
  out = negative ? -v : v;
  return true;
}

}  // namespace

std::string quoted_token(std::string_view s) {
  std::string out = "'";
  std::size_t k = 0;
  for (; k < s.size() && k < 40; ++k) {
    const auto c = static_cast<unsigned char>(s[k]);
    if (c >= 0x20 && c < 0x7f) {
      out += static_cast<char>(c);
    } else {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", c);
      out += buf;
    }
  }
  if (k < s.size()) out += "...";
  return out + "'";
}

bool parse_number(std::string_view s, double& out) {
  const char* b = s.data();
  const char* e = b + s.size();
  if (b != e && *b == '+') {
    ++b;
    if (b == e || *b == '-' || *b == '+') return false;
  }
  if (b == e) return false;
  if (parse_simple_decimal(b, e, out)) return true;
  auto [ptr, ec] = std::from_chars(b, e, out, std::chars_format::general);
  if (ec == std::errc() && ptr == e) return true;
  if (ec != std::errc::result_out_of_range || ptr != e) return false;
  // Out of range: overflow becomes inf (rejected by the caller), underflow a tiny value.
  const std::string copy(b, e);
  char* end = nullptr;
  out = std::strtod(copy.c_str(), &end);
  return end == copy.c_str() + copy.size();
}

}  // namespace tessera
