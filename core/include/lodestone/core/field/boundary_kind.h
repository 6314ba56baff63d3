#pragma once
// What the outer layer of grid nodes means to the field solve.

namespace lodestone {
inline namespace field {

enum class BoundaryKind : int {
  Open = 0,   ///< far-field (free-space) potential of the magnetization on the outer nodes
  Shield = 1  ///< the paper's Neumann wall, grad(phi).n = M.n: a superconducting box (B.n = 0)
};
const char* toString(BoundaryKind kind);

}  // namespace field
}  // namespace lodestone
