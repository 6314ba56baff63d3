#pragma once
// Gauss-Legendre quadrature nodes and weights on [-1, 1]: exact for
// polynomials of degree 2n - 1 with n points.
#include <vector>

namespace lodestone {
inline namespace base {

/// Fills `nodes` and `weights` (resized to n) with the n-point Gauss-Legendre
/// rule on [-1, 1] (Newton iteration on the Legendre polynomial P_n, nodes to
/// ~1e-16). Throws InvalidArgument unless 1 <= n <= 1000.
void gaussLegendreRule(int n, std::vector<double>& nodes, std::vector<double>& weights);

}  // namespace base
}  // namespace lodestone
