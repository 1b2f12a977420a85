// Strict decimal numbers for the model file: the lexical form is checked by hand because
// std::from_chars/strtod also accept nan, inf and hex, which the format forbids.
#include <cstdint>
#include <charconv>
#include <cmath>
#include <optional>
#include <string>
#include <string_view>

#include "format/model_lexer.h"
#include "rayfarm/model_parser.h"
#include "util/utf8.h"

namespace rayfarm {
namespace {

bool is_digit(char c) { return c >= '0' && c <= '9'; }

bool equals_nocase(std::string_view s, std::string_view lower_word) {
  return s.size() == lower_word.size() && starts_with_nocase(s, lower_word);
}

// Exact powers of ten: every one up to 1e22 is a double without rounding.
constexpr double kPow10[] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                             1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                             1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

}  // namespace

std::optional<double> parse_number(std::string_view token, std::string* why) {
  auto fail = [&](const char* reason) -> std::optional<double> {
    if (why) *why = reason;
    return std::nullopt;
  };
  std::string_view s = token;
  if (s.empty()) return fail("empty");
  std::string_view unsigned_part = s;
  if (unsigned_part[0] == '+' || unsigned_part[0] == '-') unsigned_part.remove_prefix(1);
  // The words and prefixes the format forbids, named in the message. None starts with a digit
  // but "0x" (the common case, a digit, is told apart by its first character).
  const char first = unsigned_part.empty() ? '\0' : unsigned_part[0];
  if (!is_digit(first)) {
    if (equals_nocase(unsigned_part, "nan") || starts_with_nocase(unsigned_part, "nan("))
      return fail("NaN is not allowed");
    if (equals_nocase(unsigned_part, "inf") || equals_nocase(unsigned_part, "infinity"))
      return fail("infinity is not allowed");
  } else if (first == '0' && starts_with_nocase(unsigned_part, "0x")) {
    return fail("hexadecimal numbers are not allowed");
  }

  // While checking the form, gather the significant digits: when there are few enough and
  // the power of ten is small, mantissa * 10^k (or / 10^-k) is one correctly rounded
  // operation on exact doubles, the same value from_chars gives (Clinger's fast path).
  uint64_t mantissa = 0;
  int mantissa_digits = 0;  // digits in `mantissa`, from the first non-zero one
  bool fast = true;
  auto digit = [&](char c) {
    if (mantissa == 0 && c == '0') return;
    if (++mantissa_digits > 15) {
      fast = false;
      return;
    }
    mantissa = mantissa * 10 + static_cast<uint64_t>(c - '0');
  };
  size_t i = 0;
  bool negative = s[i] == '-';
  if (s[i] == '+' || s[i] == '-') ++i;
  size_t int_digits = 0, frac_digits = 0;
  while (i < s.size() && is_digit(s[i])) digit(s[i]), ++i, ++int_digits;
  if (i < s.size() && s[i] == '.') {
    ++i;
    while (i < s.size() && is_digit(s[i])) digit(s[i]), ++i, ++frac_digits;
  }
  if (int_digits + frac_digits == 0) return fail("expected a decimal number");
  long exponent = 0;
  if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
    ++i;
    bool exp_negative = false;
    if (i < s.size() && (s[i] == '+' || s[i] == '-')) exp_negative = s[i++] == '-';
    size_t exp_digits = 0;
    while (i < s.size() && is_digit(s[i])) {
      if (exponent < 100000) exponent = exponent * 10 + (s[i] - '0');
      ++i, ++exp_digits;
    }
    if (exp_digits == 0) return fail("exponent has no digits");
    if (exp_negative) exponent = -exponent;
  }
  std::string unexpected;
  if (i != s.size()) {
    // A character that looks like a space or a minus but is not ASCII (pasted from a document)
    // is invisible in the message unless it is named.
    const size_t n = utf8_length(s, i);
    if (n > 0) {
      unexpected = "unexpected character " + code_point_name(utf8_code(s, i, n)) +
                   " after the number: numbers are separated by plain spaces";
      return fail(unexpected.c_str());
    }
    return fail("unexpected characters after the number");
  }

  if (fast) {
    long power = exponent - static_cast<long>(frac_digits);
    double m = static_cast<double>(mantissa);  // exact: below 10^15
    if (mantissa == 0) return negative ? -0.0 : 0.0;
    if (power >= -22 && power <= 22) {
      double value = power < 0 ? m / kPow10[-power] : m * kPow10[power];
      return negative ? -value : value;
    }
  }

  // from_chars takes no leading '+'.
  std::string_view body = s.front() == '+' ? s.substr(1) : s;
  double value = 0;
  auto [ptr, ec] = std::from_chars(body.data(), body.data() + body.size(), value);
  if (ec == std::errc::result_out_of_range) {
    // Out of range is overflow or underflow; tell them apart by the magnitude written.
    double probe = std::strtod(std::string(body).c_str(), nullptr);
    if (std::isinf(probe) || std::fabs(probe) >= 1.0) return fail("number is too large");
    return probe;  // underflow: strtod's denormal or zero is the nearest double
  }
  if (ec != std::errc() || ptr != body.data() + body.size()) return fail("not a number");
  if (!std::isfinite(value)) return fail("number is too large");
  return value;
}

}  // namespace rayfarm
