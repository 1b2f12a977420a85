// Strict decimal numbers for the model file: the lexical form is checked by hand because
// std::from_chars/strtod also accept nan, inf and hex, which the format forbids.
#include <cctype>
#include <charconv>
#include <cmath>
#include <optional>
#include <string>
#include <string_view>

#include "rayfarm/model_parser.h"

namespace rayfarm {
namespace {

bool is_digit(char c) { return c >= '0' && c <= '9'; }

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

}  // namespace

std::optional<double> parse_number(std::string_view token, std::string* why) {
  auto fail = [&](const char* reason) -> std::optional<double> {
    if (why) *why = reason;
    return std::nullopt;
  };
  std::string_view s = token;
  if (s.empty()) return fail("empty");
  std::string l = lower(s);
  std::string_view unsigned_part = l;
  if (!unsigned_part.empty() && (unsigned_part[0] == '+' || unsigned_part[0] == '-'))
    unsigned_part.remove_prefix(1);
  if (unsigned_part == "nan" || unsigned_part.starts_with("nan("))
    return fail("NaN is not allowed");
  if (unsigned_part == "inf" || unsigned_part == "infinity")
    return fail("infinity is not allowed");
  if (unsigned_part.starts_with("0x")) return fail("hexadecimal numbers are not allowed");

  size_t i = 0;
  if (s[i] == '+' || s[i] == '-') ++i;
  size_t int_digits = 0, frac_digits = 0;
  while (i < s.size() && is_digit(s[i])) ++i, ++int_digits;
  if (i < s.size() && s[i] == '.') {
    ++i;
    while (i < s.size() && is_digit(s[i])) ++i, ++frac_digits;
  }
  if (int_digits + frac_digits == 0) return fail("expected a decimal number");
  if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
    ++i;
    if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
    size_t exp_digits = 0;
    while (i < s.size() && is_digit(s[i])) ++i, ++exp_digits;
    if (exp_digits == 0) return fail("exponent has no digits");
  }
  if (i != s.size()) return fail("unexpected characters after the number");

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
