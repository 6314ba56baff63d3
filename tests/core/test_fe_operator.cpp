// The discrete field operator: symmetry, positive definiteness, its null space
// (no checkerboard modes, unlike node-to-node central differences), the
// residual as the gradient of the energy, and the Jacobian against finite
// differences of the residual.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <random>
#include <vector>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/field/magnetostatic_problem.h"
#include "lodestone/core/field/material.h"
#include "lodestone/core/stage/nodal_field.h"
#include "lodestone/core/base/parallel.h"
#include "lodestone/core/field/q1_element.h"

using namespace lodestone;

namespace {

struct SmallProblem {
  GridSpec grid;
  DenseGrid<double> n;
  MagneticMaterial material = paperMaterial();
};

SmallProblem randomMaterial(int N, unsigned seed) {
  SmallProblem s;
  s.grid.dx = 0.01;
  s.grid.dims = {N, N + 1, N - 1};
  s.n.reset(s.grid, 0.0);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(0, 1);
  for (std::size_t m = 0; m < s.n.size(); ++m) s.n[m] = U(rng) < 0.6 ? s.material.numberDensity * U(rng) : 0.0;
  return s;
}

AppliedFieldFunction uniform(const Vec3d& H) {
  return [H](const Vec3d*, std::size_t c, Vec3d* out) {
    for (std::size_t m = 0; m < c; ++m) out[m] = H;
  };
}

// Dense Jacobian restricted to free nodes.
Eigen::MatrixXd assemble(const MagnetostaticProblem& p, std::vector<std::size_t>* freeNodes) {
  const GridSpec& g = p.grid();
  freeNodes->clear();
  for (int k = 0; k < g.dims.k; ++k)
    for (int j = 0; j < g.dims.j; ++j)
      for (int i = 0; i < g.dims.i; ++i)
        if (p.isFree(i, j, k)) freeNodes->push_back(g.index(i, j, k));
  const std::size_t nf = freeNodes->size();
  Eigen::MatrixXd A(nf, nf);
  std::vector<double> e(g.nodeCount(), 0.0), out(g.nodeCount());
  for (std::size_t c = 0; c < nf; ++c) {
    e[(*freeNodes)[c]] = 1.0;
    p.applyJacobian(e.data(), out.data());
    e[(*freeNodes)[c]] = 0.0;
    for (std::size_t r = 0; r < nf; ++r) A(Eigen::Index(r), Eigen::Index(c)) = out[(*freeNodes)[r]];
  }
  return A;
}

}  // namespace

TEST(FeOperator, JacobianIsSymmetricPositiveDefiniteOpen) {
  SmallProblem s = randomMaterial(6, 1);
  MagnetostaticProblem p(s.grid, s.material.law, BoundaryKind::Open);
  p.setMaterial(s.n.view(), uniform({3e4, -1e4, 5e4}));
  std::vector<double> phi(s.grid.nodeCount()), F(s.grid.nodeCount());
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> U(-50, 50);
  for (double& v : phi) v = U(rng);
  p.evaluate(phi.data(), F.data());
  std::vector<std::size_t> freeNodes;
  const Eigen::MatrixXd A = assemble(p, &freeNodes);
  const double asym = (A - A.transpose()).norm() / A.norm();
  EXPECT_LT(asym, 1e-14);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(0.5 * (A + A.transpose()));
  const double lmin = eig.eigenvalues().minCoeff(), lmax = eig.eigenvalues().maxCoeff();
  EXPECT_GT(lmin, 1e-3 * lmax) << "smallest eigenvalue " << lmin << ", largest " << lmax;
}

TEST(FeOperator, ShieldNullSpaceIsTheConstantsOnly) {
  // With the Neumann (shield) wall the operator is singular, but only for
  // constants: exactly one zero eigenvalue, even on an even-sized grid where
  // node-to-node central differences have 8 null modes (the checkerboard).
  SmallProblem s = randomMaterial(6, 3);
  MagnetostaticProblem p(s.grid, s.material.law, BoundaryKind::Shield);
  p.setMaterial(s.n.view(), uniform({0, 0, 1e5}));
  std::vector<double> phi(s.grid.nodeCount(), 0.0), F(s.grid.nodeCount());
  p.evaluate(phi.data(), F.data());
  std::vector<std::size_t> freeNodes;
  const Eigen::MatrixXd A = assemble(p, &freeNodes);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(0.5 * (A + A.transpose()));
  const auto& ev = eig.eigenvalues();
  const double scale = ev.maxCoeff();
  int zeros = 0;
  for (Eigen::Index m = 0; m < ev.size(); ++m) zeros += ev[m] < 1e-10 * scale;
  EXPECT_EQ(zeros, 1);
  EXPECT_GT(ev[1], 1e-4 * scale);
  // The zero mode is the constant vector.
  const Eigen::VectorXd v0 = eig.eigenvectors().col(0);
  EXPECT_LT((v0.array() - v0.mean()).matrix().norm(), 1e-8);

  // Node-to-node central differences on the same grid: G^T G has 8 null modes.
  const GridSpec& g = s.grid;
  const Eigen::Index nn = Eigen::Index(g.nodeCount());
  Eigen::MatrixXd G = Eigen::MatrixXd::Zero(3 * nn, nn);
  for (int k = 0; k < g.dims.k; ++k)
    for (int j = 0; j < g.dims.j; ++j)
      for (int i = 0; i < g.dims.i; ++i) {
        const int p3[3] = {i, j, k}, d3[3] = {g.dims.i, g.dims.j, g.dims.k};
        for (int a = 0; a < 3; ++a) {
          if (p3[a] == 0 || p3[a] == d3[a] - 1) continue;  // interior rows only
          int lo[3] = {i, j, k}, hi[3] = {i, j, k};
          --lo[a];
          ++hi[a];
          const Eigen::Index row = 3 * Eigen::Index(g.index(i, j, k)) + a;
          G(row, Eigen::Index(g.index(hi[0], hi[1], hi[2]))) += 0.5;
          G(row, Eigen::Index(g.index(lo[0], lo[1], lo[2]))) -= 0.5;
        }
      }
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> cd(G.transpose() * G);
  int cdZeros = 0;
  for (Eigen::Index m = 0; m < cd.eigenvalues().size(); ++m)
    cdZeros += cd.eigenvalues()[m] < 1e-10 * cd.eigenvalues().maxCoeff();
  EXPECT_GE(cdZeros, 8);
}

TEST(FeOperator, ResidualIsTheEnergyGradientAndJacobianMatchesFiniteDifferences) {
  for (BoundaryKind b : {BoundaryKind::Open, BoundaryKind::Shield}) {
    SmallProblem s = randomMaterial(7, 4);
    MagnetostaticProblem p(s.grid, s.material.law, b);
    p.setMaterial(s.n.view(), uniform({4e4, 0, 6e4}));
    const std::size_t S = s.grid.nodeCount();
    std::vector<double> phi(S), d(S), F(S), Fp(S), Fm(S), Jd(S), Kx(S);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> U(-1, 1);
    for (std::size_t m = 0; m < S; ++m) {
      phi[m] = 300 * U(rng);
      d[m] = U(rng);
    }
    p.zeroFixed(d.data());
    p.evaluate(phi.data(), F.data());
    p.applyJacobian(d.data(), Jd.data());
    const double eps = 1e-3;
    std::vector<double> pp(phi), pm(phi);
    for (std::size_t m = 0; m < S; ++m) {
      pp[m] += eps * d[m];
      pm[m] -= eps * d[m];
    }
    p.evaluate(pp.data(), Fp.data());
    p.evaluate(pm.data(), Fm.data());
    double num = 0, den = 0;
    for (std::size_t m = 0; m < S; ++m) {
      const double fd = (Fp[m] - Fm[m]) / (2 * eps);
      num += (fd - Jd[m]) * (fd - Jd[m]);
      den += Jd[m] * Jd[m];
    }
    EXPECT_LT(std::sqrt(num / den), 1e-8) << toString(b);

    // Directional derivative of E = phi^T K phi / 2 + sum w W along d (d = 0 on fixed nodes).
    const auto energyAlong = [&](double t) {
      std::vector<double> x(S);
      for (std::size_t m = 0; m < S; ++m) x[m] = phi[m] + t * d[m];
      p.applyVacuum(x.data(), Kx.data());
      // Only free rows of K x are formed; the fixed-row part of the quadratic
      // is constant along d, so the difference quotient is unaffected.
      double q = 0;
      for (std::size_t m = 0; m < S; ++m) q += x[m] * Kx[m];
      return p.materialEnergyAlong(x.data(), d.data(), 0.0, nullptr) + 0.5 * q;
    };
    const double dE = (energyAlong(eps) - energyAlong(-eps)) / (2 * eps);
    const double dF = deterministicDot(d.data(), F.data(), S);
    if (b == BoundaryKind::Shield) {
      EXPECT_NEAR(dE, dF, 1e-7 * std::fabs(dF)) << toString(b);
    }
  }
}

TEST(FeOperator, ProjectedGradientIsExactForLinearAndSecondOrderInside) {
  GridSpec g;
  g.origin = {-0.1, 0.05, 0.3};
  g.dx = 0.02;
  g.dims = {7, 8, 6};
  DenseGrid<double> phi(g);
  DenseGrid<Vec3d> grad(g);
  const Vec3d c{3.0, -2.0, 0.5};
  for (int k = 0; k < g.dims.k; ++k)
    for (int j = 0; j < g.dims.j; ++j)
      for (int i = 0; i < g.dims.i; ++i) phi(i, j, k) = 7.0 + dot(c, g.nodePosition(i, j, k));
  projectedGradient(phi.view(), grad.view());
  for (std::size_t m = 0; m < grad.size(); ++m) EXPECT_LT(norm(grad[m] - c), 1e-11);

  // Smooth phi: interior error falls as dx^2.
  const auto maxInteriorError = [](int N) {
    GridSpec h;
    h.dx = 1.0 / (N - 1);
    h.dims = {N, N, N};
    DenseGrid<double> f(h);
    DenseGrid<Vec3d> df(h);
    for (int k = 0; k < N; ++k)
      for (int j = 0; j < N; ++j)
        for (int i = 0; i < N; ++i) {
          const Vec3d x = h.nodePosition(i, j, k);
          f(i, j, k) = std::sin(2 * x.x) * std::cos(x.y) * std::exp(x.z);
        }
    projectedGradient(f.view(), df.view());
    double e = 0;
    for (int k = 1; k < N - 1; ++k)
      for (int j = 1; j < N - 1; ++j)
        for (int i = 1; i < N - 1; ++i) {
          const Vec3d x = h.nodePosition(i, j, k);
          const Vec3d exact{2 * std::cos(2 * x.x) * std::cos(x.y) * std::exp(x.z),
                            -std::sin(2 * x.x) * std::sin(x.y) * std::exp(x.z),
                            std::sin(2 * x.x) * std::cos(x.y) * std::exp(x.z)};
          e = std::max(e, norm(df(i, j, k) - exact));
        }
    return e;
  };
  const double e1 = maxInteriorError(11), e2 = maxInteriorError(21);
  const double order = std::log(e1 / e2) / std::log(2.0);
  EXPECT_GT(order, 1.8) << e1 << " -> " << e2;
}

TEST(FeOperator, ProjectedGradientEqualsTheNodeByNodeFormulaBitForBit) {
  // The plane-by-plane passes against the documented formula evaluated at
  // each node alone (difference along the axis, smoothed along the next axis,
  // then the one after; one-sided and [2/3, 1/3] at the walls), on a grid
  // tall enough to be split into several chunks of planes; and the nodal H
  // against H_ext - grad phi.
  GridSpec g;
  g.origin = {0.01, -0.02, 0.03};
  g.dx = 0.004;
  g.dims = {40, 36, 53};
  DenseGrid<double> phi(g), n(g);
  DenseGrid<Vec3d> grad(g), hext(g), H(g), M(g), B(g);
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> U(-1, 1);
  for (std::size_t m = 0; m < phi.size(); ++m) {
    phi[m] = 50 * U(rng);
    hext[m] = {1e3 * U(rng), 1e3 * U(rng), 1e4 + 1e3 * U(rng)};
    n[m] = m % 3 == 0 ? 0.0 : 1e20 * (1 + U(rng));
  }
  projectedGradient(phi.view(), grad.view());
  const int dims[3] = {g.dims.i, g.dims.j, g.dims.k};
  const auto value = [&](const int c[3]) { return phi(c[0], c[1], c[2]); };
  const auto difference = [&](int c[3], int axis) {
    const int p = c[axis];
    int up[3] = {c[0], c[1], c[2]}, down[3] = {c[0], c[1], c[2]};
    ++up[axis];
    --down[axis];
    if (p == 0) return (value(up) - value(c)) * (1.0 / g.dx);
    if (p == dims[axis] - 1) return (value(c) - value(down)) * (1.0 / g.dx);
    return (value(up) - value(down)) * (0.5 / g.dx);
  };
  const auto smooth = [&](int c[3], int along, const auto& inner) {
    const int p = c[along];
    int up[3] = {c[0], c[1], c[2]}, down[3] = {c[0], c[1], c[2]};
    ++up[along];
    --down[along];
    if (p == 0) return (2.0 / 3) * inner(c) + (1.0 / 3) * inner(up);
    if (p == dims[along] - 1) return (2.0 / 3) * inner(c) + (1.0 / 3) * inner(down);
    return (2.0 / 3) * inner(c) + (1.0 / 6) * (inner(up) + inner(down));
  };
  for (int k = 0; k < g.dims.k; ++k)
    for (int j = 0; j < g.dims.j; ++j)
      for (int i = 0; i < g.dims.i; ++i) {
        int c[3] = {i, j, k};
        for (int axis = 0; axis < 3; ++axis) {
          const int s1 = (axis + 1) % 3, s2 = (axis + 2) % 3;
          const double expected = smooth(c, s2, [&](int* q) {
            return smooth(q, s1, [&](int* r) { return difference(r, axis); });
          });
          ASSERT_EQ(grad(i, j, k)[axis], expected) << "node (" << i << ", " << j << ", " << k << "), axis " << axis;
        }
      }
  GridScratch scratch;
  recoverNodalFields(phi.view(), hext.view(), n.view(), paperMaterial().law, H.view(), M.view(), B.view(),
                     &scratch);
  for (std::size_t m = 0; m < phi.size(); ++m) {
    const Vec3d h = hext[m] - grad[m];
    ASSERT_TRUE(H[m] == h) << "node " << m;
    ASSERT_TRUE(M[m] == magnetization(paperMaterial().law, n[m], h)) << "node " << m;
    ASSERT_TRUE(B[m] == kMu0 * (h + M[m])) << "node " << m;
  }
}

// The Newton loop updates K phi after a wall update through the wall layer
// only: addWallCoupling must add exactly what applyVacuum gives for the wall
// values alone, fixedNodes must list exactly the non-free nodes, and the
// evaluation from a given vacuum part must equal the full one.
TEST(FeOperator, WallCouplingEqualsTheVacuumStencilOfTheWallValues) {
  SmallProblem s = randomMaterial(7, 3);
  MagnetostaticProblem p(s.grid, s.material.law, BoundaryKind::Open);
  p.setMaterial(s.n.view(), uniform({1e4, 2e4, -3e4}));
  const GridSpec& g = s.grid;
  std::vector<double> v(g.nodeCount()), wallOnly(g.nodeCount(), 0.0);
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> U(-1, 1);
  for (double& x : v) x = U(rng);
  const std::vector<std::size_t> wall = p.fixedNodes();
  std::size_t expected = 0;
  for (int k = 0; k < g.dims.k; ++k)
    for (int j = 0; j < g.dims.j; ++j)
      for (int i = 0; i < g.dims.i; ++i) expected += p.isFree(i, j, k) ? 0 : 1;
  ASSERT_EQ(wall.size(), expected);
  for (std::size_t m = 1; m < wall.size(); ++m) ASSERT_LT(wall[m - 1], wall[m]);
  for (std::size_t m : wall) {
    const int i = int(m % std::size_t(g.dims.i)), j = int(m / std::size_t(g.dims.i) % std::size_t(g.dims.j)),
              k = int(m / (std::size_t(g.dims.i) * std::size_t(g.dims.j)));
    ASSERT_FALSE(p.isFree(i, j, k)) << "node " << m;
    wallOnly[m] = v[m];
  }
  std::vector<double> ref(g.nodeCount()), out(g.nodeCount(), 0.5);
  p.applyVacuum(wallOnly.data(), ref.data());
  std::vector<double> base = out;
  p.addWallCoupling(v.data(), out.data());  // free values of v must be ignored
  double worst = 0, scale = 0;
  for (std::size_t m = 0; m < g.nodeCount(); ++m) {
    worst = std::max(worst, std::fabs((out[m] - base[m]) - ref[m]));
    scale = std::max(scale, std::fabs(ref[m]));
  }
  EXPECT_GT(scale, 0.0);
  EXPECT_LT(worst, 1e-14 * scale + 1e-300);

  std::vector<double> Kphi(g.nodeCount()), F1(g.nodeCount()), F2(g.nodeCount());
  p.applyVacuum(v.data(), Kphi.data());
  const auto e1 = p.evaluate(v.data(), F1.data());
  const auto e2 = p.evaluate(v.data(), F2.data(), true, Kphi.data());
  EXPECT_EQ(F1, F2);
  EXPECT_EQ(e1.materialEnergy, e2.materialEnergy);

  MagnetostaticProblem shield(s.grid, s.material.law, BoundaryKind::Shield);
  EXPECT_TRUE(shield.fixedNodes().empty());
}

// The sum-factorized Gauss-point gradients and their transpose must equal
// the element tables' dN sums (what the residual and energy are defined by).
TEST(FeOperator, SumFactorizedGaussGradientsMatchTheShapeTables) {
  const q1::Tables t = q1::makeTables();
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> U(-1, 1);
  for (int trial = 0; trial < 20; ++trial) {
    double v[8], grad[8][3], f[8][3], out[8];
    for (double& x : v) x = U(rng);
    q1::gaussGradients(v, grad);
    for (int q = 0; q < 8; ++q) {
      const Vec3d ref = q1::referenceGradient(t, q, v);
      for (int a = 0; a < 3; ++a) EXPECT_NEAR(grad[q][a], ref[a], 1e-15) << "q " << q << " axis " << a;
      for (int a = 0; a < 3; ++a) f[q][a] = U(rng);
    }
    q1::gaussDivergenceTranspose(f, out);
    for (int c = 0; c < 8; ++c) {
      double ref = 0;
      for (int q = 0; q < 8; ++q) ref += dot(t.dN[q][c], Vec3d{f[q][0], f[q][1], f[q][2]});
      EXPECT_NEAR(out[c], ref, 1e-14) << "corner " << c;
    }
  }
}

TEST(FeOperator, FusedJacobianProductAndDotEqualTheSeparateOnes) {
  // applyJacobianDot (one pass over the rows) against applyJacobian and a
  // dot product, for both boundaries, with material touching the walls.
  for (BoundaryKind b : {BoundaryKind::Open, BoundaryKind::Shield}) {
    SmallProblem s = randomMaterial(9, 6);
    MagnetostaticProblem p(s.grid, s.material.law, b);
    p.setMaterial(s.n.view(), uniform({2e4, 5e4, -3e4}));
    const std::size_t S = s.grid.nodeCount();
    std::vector<double> phi(S), v(S), F(S), Jv(S), Jv2(S);
    std::mt19937 rng(8);
    std::uniform_real_distribution<double> U(-1, 1);
    for (std::size_t m = 0; m < S; ++m) {
      phi[m] = 100 * U(rng);
      v[m] = U(rng);
    }
    p.evaluate(phi.data(), F.data());
    p.applyJacobian(v.data(), Jv.data());
    const double dot = p.applyJacobianDot(v.data(), Jv2.data());
    double num = 0, den = 0;
    for (std::size_t m = 0; m < S; ++m) {
      num += (Jv2[m] - Jv[m]) * (Jv2[m] - Jv[m]);
      den += Jv[m] * Jv[m];
    }
    EXPECT_LT(std::sqrt(num / den), 1e-14) << toString(b);
    const double ref = deterministicDot(v.data(), Jv.data(), S);
    EXPECT_NEAR(dot, ref, 1e-12 * std::fabs(ref)) << toString(b);
    EXPECT_GT(dot, 0) << toString(b);
  }
}

namespace {
// Relative difference of two block-multipole lists (dipoles and quadrupoles
// together), on the scale of the larger.
double multipoleDifference(const std::vector<Multipole>& a, const std::vector<Multipole>& b) {
  double diff = 0, scale = 0;
  for (std::size_t m = 0; m < a.size(); ++m) {
    diff += norm2(a[m].dipole - b[m].dipole);
    scale += std::max(norm2(a[m].dipole), norm2(b[m].dipole));
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        const double d = a[m].quadrupole[i][j] - b[m].quadrupole[i][j];
        diff += d * d / 1e-4;  // N is a dipole times a length (~1 cm here)
        scale += std::max(a[m].quadrupole[i][j] * a[m].quadrupole[i][j], b[m].quadrupole[i][j] * b[m].quadrupole[i][j]) / 1e-4;
      }
  }
  return std::sqrt(diff / scale);
}
}  // namespace

TEST(FeOperator, LinearizedMultipolesAreTheFirstOrderChangeOfTheEvaluatedOnes) {
  // Material everywhere at one density, so that dM/dH is the same at the 8
  // Gauss points of a cell where the field is (the linear law everywhere;
  // the Langevin law at phi = 0 in a uniform applied field): there the
  // cell-mean tensor is exact and linearizedMultipoles(dphi) must equal the
  // change of Evaluation::multipoles to first order.
  GridSpec g;
  g.dx = 0.01;
  g.dims = {20, 18, 17};  // more than one multipole block along each axis
  const DenseGrid<double> n(g, paperMaterial().numberDensity);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(-1, 1);
  std::vector<double> dphi(g.nodeCount());
  for (double& v : dphi) v = 30.0 * U(rng);
  std::vector<double> F(g.nodeCount());
  const auto multipolesAt = [&](MagnetostaticProblem& p, const std::vector<double>& phi) {
    return p.evaluate(phi.data(), F.data(), true).multipoles;
  };
  {
    MagnetostaticProblem p(g, linearized(paperMaterial()).law, BoundaryKind::Open);
    p.setMaterial(n.view(), uniform({2e4, -1e4, 6e4}));
    std::vector<double> phi(g.nodeCount());
    for (double& v : phi) v = 200.0 * U(rng);
    std::vector<double> shifted(phi);
    for (std::size_t m = 0; m < phi.size(); ++m) shifted[m] += dphi[m];
    const std::vector<Multipole> after = multipolesAt(p, shifted);
    const std::vector<Multipole> before = multipolesAt(p, phi);  // the tensors at phi (the same: linear)
    ASSERT_GT(p.multipoleBlockCount(), 1u);
    std::vector<Multipole> change = after;
    for (std::size_t b = 0; b < change.size(); ++b) {
      change[b].dipole = after[b].dipole - before[b].dipole;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) change[b].quadrupole[i][j] = after[b].quadrupole[i][j] - before[b].quadrupole[i][j];
    }
    const std::vector<Multipole> lin = p.linearizedMultipoles(dphi.data());
    ASSERT_EQ(lin.size(), change.size());
    for (std::size_t b = 0; b < lin.size(); ++b) EXPECT_EQ(norm(lin[b].centre - before[b].centre), 0.0);
    EXPECT_LT(multipoleDifference(lin, change), 1e-11);
  }
  {
    MagnetostaticProblem p(g, paperMaterial().law, BoundaryKind::Open);
    p.setMaterial(n.view(), uniform({1e4, 3e4, -5e4}));
    const std::vector<double> zero(g.nodeCount(), 0.0);
    const double eps = 1e-3;
    std::vector<double> plus(g.nodeCount()), minus(g.nodeCount());
    for (std::size_t m = 0; m < zero.size(); ++m) {
      plus[m] = eps * dphi[m];
      minus[m] = -eps * dphi[m];
    }
    std::vector<Multipole> fd = multipolesAt(p, plus);
    const std::vector<Multipole> lo = multipolesAt(p, minus);
    for (std::size_t b = 0; b < fd.size(); ++b) {
      fd[b].dipole = (fd[b].dipole - lo[b].dipole) / (2 * eps);
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) fd[b].quadrupole[i][j] = (fd[b].quadrupole[i][j] - lo[b].quadrupole[i][j]) / (2 * eps);
    }
    multipolesAt(p, zero);  // the tensors at phi = 0
    const double err = multipoleDifference(p.linearizedMultipoles(dphi.data()), fd);
    EXPECT_LT(err, 1e-6);
    EXPECT_GT(err, 0.0);  // a genuine finite difference, not the same numbers
  }
}

TEST(FeOperator, ASetAgainProblemMatchesAFreshOneBitForBit) {
  // One problem set again and again (as in a simulation: the same cells
  // with a new density, then moved cells, then the first material again)
  // against a fresh problem per material: the residual, the multipole
  // blocks (their cells, centres and moments), the Jacobian's element
  // tensors and its product, bit for bit.
  const AppliedFieldFunction uniform = [](const Vec3d*, std::size_t c, Vec3d* out) {
    for (std::size_t m = 0; m < c; ++m) out[m] = {2e3, -1e3, 4e4};
  };
  SmallProblem first = randomMaterial(11, 31);
  SmallProblem denser = first, moved = randomMaterial(11, 32);
  for (std::size_t m = 0; m < denser.n.size(); ++m) denser.n[m] *= 1.0 + 0.5 * double(m % 7) / 7.0;
  for (int k = 0; k < moved.grid.dims.k; ++k)
    for (int j = 0; j < moved.grid.dims.j; ++j)
      for (int i = 0; i < moved.grid.dims.i; ++i)
        if (i < 3) moved.n(i, j, k) = 0;
  std::vector<double> phi(first.grid.nodeCount()), dphi(phi.size());
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> U(-1, 1);
  for (double& v : phi) v = 20 * U(rng);
  for (double& v : dphi) v = U(rng);
  const auto same = [](const std::vector<Multipole>& a, const std::vector<Multipole>& b) {
    if (a.size() != b.size()) return false;
    for (std::size_t m = 0; m < a.size(); ++m) {
      if (!(a[m].centre == b[m].centre) || !(a[m].dipole == b[m].dipole)) return false;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          if (a[m].quadrupole[i][j] != b[m].quadrupole[i][j]) return false;
    }
    return true;
  };
  MagnetostaticProblem kept(first.grid, first.material.law, BoundaryKind::Open);
  for (const SmallProblem* p : {&first, &denser, &moved, &first}) {
    kept.setMaterial(p->n.view(), uniform);
    MagnetostaticProblem fresh(p->grid, p->material.law, BoundaryKind::Open);
    fresh.setMaterial(p->n.view(), uniform);
    ASSERT_EQ(kept.materialCellCount(), fresh.materialCellCount());
    ASSERT_EQ(kept.multipoleBlockCount(), fresh.multipoleBlockCount());
    std::vector<double> a(phi.size()), b(phi.size());
    const MagnetostaticProblem::Evaluation ea = kept.evaluate(phi.data(), a.data());
    const MagnetostaticProblem::Evaluation eb = fresh.evaluate(phi.data(), b.data());
    for (std::size_t m = 0; m < a.size(); ++m) ASSERT_EQ(a[m], b[m]) << "residual, node " << m;
    EXPECT_TRUE(same(ea.multipoles, eb.multipoles));
    EXPECT_TRUE(same(kept.linearizedMultipoles(dphi.data()), fresh.linearizedMultipoles(dphi.data())));
    for (std::size_t s = 0; s < kept.materialCellCount(); ++s) {
      const SymMat3d& ta = kept.materialCellTensor(s);
      const SymMat3d& tb = fresh.materialCellTensor(s);
      ASSERT_TRUE(ta.xx == tb.xx && ta.yy == tb.yy && ta.zz == tb.zz && ta.xy == tb.xy && ta.xz == tb.xz &&
                  ta.yz == tb.yz)
          << "cell " << s;
    }
    kept.applyJacobian(dphi.data(), a.data());
    fresh.applyJacobian(dphi.data(), b.data());
    for (std::size_t m = 0; m < a.size(); ++m) ASSERT_EQ(a[m], b[m]) << "Jacobian product, node " << m;
  }
}

TEST(FeOperator, KeptAppliedFieldEvaluatesOnlyNewCellsAndMatchesAFreshEvaluation) {
  // A non-uniform applied field that counts the points it is asked for.
  std::atomic<std::size_t> points{0};
  const AppliedFieldFunction dipoleLike = [&points](const Vec3d* x, std::size_t c, Vec3d* out) {
    points += c;
    for (std::size_t m = 0; m < c; ++m) {
      const Vec3d r = x[m] - Vec3d{0.02, -0.01, -0.3};
      const double d = norm(r);
      out[m] = 1e4 * (3 * r.z * r / (d * d) - Vec3d{0, 0, 1}) / (d * d * d);
    }
  };
  SmallProblem first = randomMaterial(9, 21), second = randomMaterial(9, 22);
  // Clear a slab of each so that cells leave and enter the material.
  for (int k = 0; k < first.grid.dims.k; ++k)
    for (int j = 0; j < first.grid.dims.j; ++j)
      for (int i = 0; i < first.grid.dims.i; ++i) {
        if (i < 2) first.n(i, j, k) = 0;
        if (i > 6) second.n(i, j, k) = 0;
      }
  MagnetostaticProblem kept(first.grid, first.material.law, BoundaryKind::Open);
  kept.setMaterial(first.n.view(), dipoleLike);
  EXPECT_EQ(kept.appliedFieldCellsEvaluated(), kept.materialCellCount());
  std::vector<std::size_t> before;
  for (std::size_t s = 0; s < kept.materialCellCount(); ++s) before.push_back(kept.materialCellBase(s));
  std::sort(before.begin(), before.end());

  points = 0;
  kept.setMaterial(second.n.view(), dipoleLike, true);
  std::size_t fresh = 0;
  for (std::size_t s = 0; s < kept.materialCellCount(); ++s)
    fresh += std::binary_search(before.begin(), before.end(), kept.materialCellBase(s)) ? 0 : 1;
  ASSERT_GT(fresh, 0u);
  ASSERT_LT(fresh, kept.materialCellCount() / 2);  // most cells are kept
  EXPECT_EQ(kept.appliedFieldCellsEvaluated(), fresh);
  EXPECT_EQ(points.load(), 8 * fresh);

  // The same residual, bit for bit, as a problem that evaluated every cell.
  MagnetostaticProblem full(second.grid, second.material.law, BoundaryKind::Open);
  full.setMaterial(second.n.view(), dipoleLike);
  std::vector<double> phi(second.grid.nodeCount()), a(phi.size()), b(phi.size());
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> U(-1, 1);
  for (double& v : phi) v = 20 * U(rng);
  kept.evaluate(phi.data(), a.data());
  full.evaluate(phi.data(), b.data());
  for (std::size_t m = 0; m < a.size(); ++m) ASSERT_EQ(a[m], b[m]) << "node " << m;

  // The same cells again: nothing is evaluated, nothing changes.
  points = 0;
  kept.setMaterial(second.n.view(), dipoleLike, true);
  EXPECT_EQ(kept.appliedFieldCellsEvaluated(), 0u);
  EXPECT_EQ(points.load(), 0u);
  kept.evaluate(phi.data(), a.data());
  for (std::size_t m = 0; m < a.size(); ++m) ASSERT_EQ(a[m], b[m]) << "node " << m;

  // Not vouched for (or after a failed call): every cell is evaluated again.
  kept.setMaterial(first.n.view(), dipoleLike, false);
  EXPECT_EQ(kept.appliedFieldCellsEvaluated(), kept.materialCellCount());
  DenseGrid<double> bad = second.n;
  bad[bad.size() / 2] = -1;
  EXPECT_THROW(kept.setMaterial(bad.view(), dipoleLike, true), InvalidArgument);
  kept.setMaterial(second.n.view(), dipoleLike, true);
  EXPECT_EQ(kept.appliedFieldCellsEvaluated(), kept.materialCellCount());
}
