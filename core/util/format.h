#pragma once
// printf-style formatting of one number for messages and reports.
#include <cstdio>
#include <string>

namespace organsim {

inline std::string format_number(double v, const char* spec = "%.4g") {
  char buf[64];
  std::snprintf(buf, sizeof buf, spec, v);
  return buf;
}

}  // namespace organsim
