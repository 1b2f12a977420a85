// How grading writes a fraction and a metric for people: one way in a test's message and in
// its metrics line, so that the two never disagree (0.0003% beside 0%).
#pragma once

#include <cstdio>
#include <string>

namespace rayfarm::grading {

// A fraction as a percentage: two decimals, or four below 0.01% (one pixel of 640x480 shows).
inline std::string percent(double f) {
  char buf[32];
  std::snprintf(buf, sizeof buf, f > 0 && f < 0.0001 ? "%.4f%%" : "%.2f%%", 100 * f);
  return buf;
}

// A metric to four significant digits (a mean difference of 1e-06 is not 0).
inline std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}

}  // namespace rayfarm::grading
