#include "lodestone/core/base/gauss_legendre.h"

#include <cmath>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/error.h"

namespace lodestone {
inline namespace base {

void gaussLegendreRule(int n, std::vector<double>& nodes, std::vector<double>& weights) {
  require(n >= 1 && n <= 1000, "Gauss-Legendre rule: the number of points must be in [1, 1000], got ",
          n);
  nodes.assign(std::size_t(n), 0.0);
  weights.assign(std::size_t(n), 0.0);
  for (int i = 0; i < n; ++i) {
    double z = std::cos(kPi * (i + 0.75) / (n + 0.5));
    double dp = 1;
    for (int it = 0; it < 100; ++it) {
      double p0 = 1, p1 = z;
      for (int j = 2; j <= n; ++j) {
        const double p2 = ((2.0 * j - 1) * z * p1 - (j - 1.0) * p0) / j;
        p0 = p1;
        p1 = p2;
      }
      dp = n * (z * p1 - p0) / (z * z - 1);
      const double dz = p1 / dp;
      z -= dz;
      if (std::fabs(dz) < 1e-16) break;
    }
    nodes[std::size_t(i)] = z;
    weights[std::size_t(i)] = 2.0 / ((1 - z * z) * dp * dp);
  }
}

}  // namespace base
}  // namespace lodestone
