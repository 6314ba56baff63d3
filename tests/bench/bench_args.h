#pragma once
// Command-line helpers shared by the benchmark programs.
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "lodestone/core/base/error.h"

namespace lodestone::bench {

/// Comma-separated finite numbers ("64,128"); throws InvalidArgument naming
/// the option (`what`) and the bad item.
inline std::vector<double> parseList(const std::string& s, const char* what) {
  std::vector<double> v;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) {
    char* end = nullptr;
    const double x = std::strtod(item.c_str(), &end);
    if (item.empty() || *end != '\0' || !std::isfinite(x))
      throw InvalidArgument(concat(what, ": bad value '", item, "'"));
    v.push_back(x);
  }
  return v;
}

}  // namespace lodestone::bench
