// The field-solve operators of the host reference backend checked against
// their definitions (the residual is the energy's gradient, the Jacobian the
// residual's derivative and symmetric, restriction the transpose of
// prolongation), and every device kernel against the host reference on the
// same inputs (skipped without a device).
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "field_backend.h"
#include "gpu_test_support.h"
#include "lodestone/gpu/magnetic_force.h"

using namespace lodestone;
using namespace lodestone::gpu;
using namespace lodestone::gpu::test;
using lodestone::gpu::detail::FieldBackend;
using lodestone::gpu::detail::FieldProblemData;

namespace {

// A non-cubic grid (odd and even node counts) with a blob of varying density
// that touches one wall, in a non-uniform applied field.
GridSpec testGrid() { return GridSpec{{-0.06, -0.05, -0.055}, 0.01, {13, 12, 11}}; }

std::vector<double> blobDensity(const GridSpec& g) {
  std::vector<double> n(g.nodeCount(), 0.0);
  for (int k = 0; k < g.dims.k; ++k)
    for (int j = 0; j < g.dims.j; ++j)
      for (int i = 0; i < g.dims.i; ++i) {
        const Vec3d x = g.nodePosition(i, j, k) - Vec3d{0.01, 0.0, -0.03};
        const double r = norm(x);
        if (r < 0.035) n[g.index(i, j, k)] = paperDensity() * (1.0 - 0.5 * r / 0.035);
      }
  return n;
}

void appliedField(const Vec3d* x, std::size_t count, Vec3d* H) {
  for (std::size_t m = 0; m < count; ++m) H[m] = Vec3d{2e4 + 1e5 * x[m].y, -1e4, 8e4 + 3e6 * x[m].z};  // A/m
}

FieldProblemData problem(bool shield) {
  const GridSpec g = testGrid();
  const std::vector<double> n = blobDensity(g);
  return gpu::detail::prepareProblem(g, paperLaw(), shield, n.data(), appliedField);
}

std::vector<double> randomVector(std::size_t n, unsigned seed, double scale) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-scale, scale);
  std::vector<double> v(n);
  for (double& x : v) x = u(rng);
  return v;
}

// A backend vector holding host values.
double* put(FieldBackend& be, const std::vector<double>& v) {
  double* p = be.allocate(v.size());
  be.upload(v.data(), v.size(), p);
  return p;
}
std::vector<double> get(FieldBackend& be, const double* p, std::size_t n) {
  std::vector<double> v(n);
  be.download(p, n, v.data());
  return v;
}

double dotHost(const std::vector<double>& a, const std::vector<double>& b) {
  double s = 0;
  for (std::size_t m = 0; m < a.size(); ++m) s += a[m] * b[m];
  return s;
}

}  // namespace

TEST(GpuFieldKernelsHost, ResidualIsTheGradientOfTheEnergy) {
  auto be = gpu::detail::makeHostFieldBackend();
  be->setProblem(problem(true));
  const std::size_t n = be->nodeCount();
  ASSERT_GT(be->materialCellCount(), 100u);
  const std::vector<double> phiH = randomVector(n, 1, 300.0), dH = randomVector(n, 2, 300.0);
  double* phi = put(*be, phiH);
  double* d = put(*be, dH);
  double* F = be->allocate(n);
  double* Kphi = be->allocate(n);
  be->evaluate(phi, F, false);
  be->applyVacuum(phi, Kphi);
  // dE/dlambda at 0 of E(phi + lambda d) = 1/2 (phi + lambda d) K (phi + lambda d) + W.
  const double eps = 1e-4;
  const double dW = (be->energyAlong(phi, d, eps, nullptr) - be->energyAlong(phi, d, -eps, nullptr)) / (2 * eps);
  const double slope = be->dot(n, d, Kphi) + dW;
  const double Fd = be->dot(n, F, d);
  EXPECT_LT(relativeScalar(slope, Fd), 1e-6) << "dE/dlambda " << slope << ", F.d " << Fd;
}

TEST(GpuFieldKernelsHost, JacobianIsTheDerivativeOfTheResidualAndSymmetric) {
  for (bool shield : {true, false}) {
    auto be = gpu::detail::makeHostFieldBackend();
    be->setProblem(problem(shield));
    const std::size_t n = be->nodeCount();
    const std::vector<double> phiH = randomVector(n, 3, 300.0), vH = randomVector(n, 4, 1.0),
                              uH = randomVector(n, 5, 1.0);
    double* phi = put(*be, phiH);
    double* F = be->allocate(n);
    be->evaluate(phi, F, true);
    double* v = put(*be, vH);
    double* u = put(*be, uH);
    be->zeroFixed(0, v);
    be->zeroFixed(0, u);
    double* Jv = be->allocate(n);
    double* Ju = be->allocate(n);
    be->applyLevel(0, v, Jv);
    be->applyLevel(0, u, Ju);
    EXPECT_LT(relativeScalar(be->dot(n, u, Jv), be->dot(n, v, Ju)), 1e-12) << "shield " << shield;
    // Central difference of F along v (J is the exact Hessian of the energy).
    const double eps = 1e-2;
    double* p1 = be->allocate(n);
    double* F1 = be->allocate(n);
    double* F2 = be->allocate(n);
    be->axpby(n, 1.0, phi, eps, v, p1);
    be->evaluate(p1, F1, false);
    be->axpby(n, 1.0, phi, -eps, v, p1);
    be->evaluate(p1, F2, false);
    be->axpby(n, 0.5 / eps, F1, -0.5 / eps, F2, F1);
    const std::vector<double> fd = get(*be, F1, n), jv = get(*be, Jv, n);
    EXPECT_LT(relativeDifference(fd, jv), 1e-6) << "shield " << shield;
    // diag(J) against e_m^T J e_m at a few material nodes.
    be->evaluate(phi, F, true);
    be->buildPreconditioner(false, 5);
    const std::vector<double> inv = get(*be, be->inverseDiagonal(0, true), n);
    for (std::size_t m : {std::size_t(7 + 13 * (6 + 12 * 2)), std::size_t(6 + 13 * (5 + 12 * 3))}) {
      std::vector<double> e(n, 0.0);
      e[m] = 1.0;
      double* pe = put(*be, e);
      be->applyLevel(0, pe, Jv);
      EXPECT_LT(relativeScalar(1.0 / inv[m], get(*be, Jv, n)[m]), 1e-13);
    }
  }
}

TEST(GpuFieldKernelsHost, CoarseOperatorsAreSymmetricAndRestrictionIsTheTransposeOfProlongation) {
  auto be = gpu::detail::makeHostFieldBackend();
  be->setProblem(problem(false));
  const std::size_t n = be->nodeCount();
  double* phi = put(*be, randomVector(n, 6, 300.0));
  double* F = be->allocate(n);
  be->evaluate(phi, F, true);
  be->buildPreconditioner(true, 3);
  ASSERT_GE(be->levelCount(), 3);
  for (int l = 0; l + 1 < be->levelCount(); ++l) {
    const std::size_t nf = be->levelNodes(l), nc = be->levelNodes(l + 1);
    const std::vector<double> f = randomVector(nf, 7 + unsigned(l), 1.0), c = randomVector(nc, 17 + unsigned(l), 1.0);
    std::vector<double> Rf(nc), Pc(nf);
    double* pf = put(*be, f);
    double* pc = put(*be, c);
    double* pRf = be->allocate(nc);
    double* pPc = be->allocate(nf);
    be->restrictTo(l, pf, pRf);
    be->prolong(l, pc, pPc);
    Rf = get(*be, pRf, nc);
    Pc = get(*be, pPc, nf);
    EXPECT_LT(relativeScalar(dotHost(Rf, c), dotHost(f, Pc)), 1e-13) << "level " << l;
    // Coarse operator symmetric on free nodes.
    if (l + 1 < be->levelCount()) {
      std::vector<double> u = randomVector(nc, 27 + unsigned(l), 1.0), v = randomVector(nc, 37 + unsigned(l), 1.0);
      double* pu = put(*be, u);
      double* pv = put(*be, v);
      be->zeroFixed(l + 1, pu);
      be->zeroFixed(l + 1, pv);
      double* Au = be->allocate(nc);
      double* Av = be->allocate(nc);
      be->applyLevel(l + 1, pu, Au);
      be->applyLevel(l + 1, pv, Av);
      EXPECT_LT(relativeScalar(be->dot(nc, pu, Av), be->dot(nc, pv, Au)), 1e-12) << "level " << l + 1;
    }
  }
}

// --- Device against host, same inputs. Relative differences are
// max|device - host| / max|host| per quantity; the bound 1e-11 allows for
// the device's fused multiply-adds and different summation order only.
namespace {
constexpr double kParity = 1e-11;
}

TEST(GpuFieldKernelsDevice, EveryOperatorMatchesTheHostReference) {
  LODESTONE_REQUIRE_DEVICE();
  for (bool shield : {true, false}) {
    SCOPED_TRACE(shield ? "shield" : "open");
    const FieldProblemData data = problem(shield);
    auto host = gpu::detail::makeHostFieldBackend();
    auto dev = gpu::detail::makeDeviceFieldBackend();
    host->setProblem(data);
    dev->setProblem(data);
    const std::size_t n = host->nodeCount();
    ASSERT_EQ(dev->nodeCount(), n);
    const std::vector<double> phiH = randomVector(n, 11, 300.0), vH = randomVector(n, 12, 1.0),
                              dH = randomVector(n, 13, 30.0);
    struct Side {
      FieldBackend* be;
      double *phi, *v, *d, *F, *out;
    };
    Side s[2];
    FieldBackend* bes[2] = {host.get(), dev.get()};
    for (int b = 0; b < 2; ++b)
      s[b] = {bes[b], put(*bes[b], phiH), put(*bes[b], vH), put(*bes[b], dH), bes[b]->allocate(n), bes[b]->allocate(n)};
    // Residual at zero.
    for (auto& x : s) x.be->residualAtZero(x.F);
    EXPECT_LT(relativeDifference(get(*dev, s[1].F, n), get(*host, s[0].F, n)), kParity) << "F0";
    // Evaluation with the Jacobian.
    gpu::detail::Evaluation ev[2];
    for (int b = 0; b < 2; ++b) ev[b] = s[b].be->evaluate(s[b].phi, s[b].F, true);
    EXPECT_LT(relativeDifference(get(*dev, s[1].F, n), get(*host, s[0].F, n)), kParity) << "F";
    EXPECT_LT(relativeScalar(ev[1].energy, ev[0].energy), kParity) << "energy";
    EXPECT_LT(relativeScalar(ev[1].energyAbs, ev[0].energyAbs), kParity) << "energyAbs";
    EXPECT_EQ(ev[1].finite, ev[0].finite);
    // Vacuum, Jacobian.
    for (auto& x : s) x.be->applyVacuum(x.v, x.out);
    EXPECT_LT(relativeDifference(get(*dev, s[1].out, n), get(*host, s[0].out, n)), kParity) << "K v";
    for (auto& x : s) x.be->applyLevel(0, x.v, x.out);
    EXPECT_LT(relativeDifference(get(*dev, s[1].out, n), get(*host, s[0].out, n)), kParity) << "J v";
    // Energy along a direction, dot products, mean removal.
    double abs[2];
    const double e0 = host->energyAlong(s[0].phi, s[0].d, 0.37, &abs[0]);
    const double e1 = dev->energyAlong(s[1].phi, s[1].d, 0.37, &abs[1]);
    EXPECT_LT(relativeScalar(e1, e0), kParity) << "energy along";
    EXPECT_LT(relativeScalar(abs[1], abs[0]), kParity) << "|energy| along";
    EXPECT_LT(relativeScalar(dev->dot(n, s[1].v, s[1].phi), host->dot(n, s[0].v, s[0].phi)), kParity) << "dot";
    // Preconditioners: Jacobi diagonal, multigrid levels.
    for (auto& x : s) x.be->buildPreconditioner(true, 3);
    ASSERT_EQ(dev->levelCount(), host->levelCount());
    EXPECT_LT(
        relativeDifference(get(*dev, dev->inverseDiagonal(0, true), n), get(*host, host->inverseDiagonal(0, true), n)),
        kParity)
        << "1/diag(J)";
    for (int l = 0; l < host->levelCount(); ++l) {
      SCOPED_TRACE(::testing::Message() << "level " << l);
      const std::size_t nl = host->levelNodes(l);
      ASSERT_EQ(dev->levelNodes(l), nl);
      EXPECT_LT(relativeDifference(get(*dev, dev->inverseDiagonal(l, false), nl),
                                   get(*host, host->inverseDiagonal(l, false), nl)),
                kParity);
      const std::vector<double> w = randomVector(nl, 50 + unsigned(l), 1.0);
      double* pw[2] = {put(*host, w), put(*dev, w)};
      double* po[2] = {host->allocate(nl), dev->allocate(nl)};
      for (int b = 0; b < 2; ++b) bes[b]->applyLevel(l, pw[b], po[b]);
      EXPECT_LT(relativeDifference(get(*dev, po[1], nl), get(*host, po[0], nl)), kParity) << "A_l w";
      if (l + 1 < host->levelCount()) {
        const std::size_t nc = host->levelNodes(l + 1);
        double* pc[2] = {host->allocate(nc), dev->allocate(nc)};
        for (int b = 0; b < 2; ++b) bes[b]->restrictTo(l, pw[b], pc[b]);
        EXPECT_LT(relativeDifference(get(*dev, pc[1], nc), get(*host, pc[0], nc)), kParity) << "restrict";
        for (int b = 0; b < 2; ++b) bes[b]->prolong(l, pc[b], po[b]);
        EXPECT_LT(relativeDifference(get(*dev, po[1], nl), get(*host, po[0], nl)), kParity) << "prolong";
      }
    }
  }
}

TEST(GpuFieldKernelsDevice, NodalFieldsAndForceMatchTheHostReference) {
  LODESTONE_REQUIRE_DEVICE();
  const GridSpec g = testGrid();
  const std::vector<double> n = blobDensity(g);
  const std::vector<double> phi = randomVector(g.nodeCount(), 21, 300.0);
  std::vector<Vec3d> hext(g.nodeCount()), x(g.nodeCount());
  for (int k = 0; k < g.dims.k; ++k)
    for (int j = 0; j < g.dims.j; ++j)
      for (int i = 0; i < g.dims.i; ++i) x[g.index(i, j, k)] = g.nodePosition(i, j, k);
  appliedField(x.data(), x.size(), hext.data());
  MagneticForceInput in;
  in.phi = phi.data();
  in.hext = hext.data();
  in.n = n.data();
  for (bool mask : {true, false}) {
    in.maskMaterial = mask;
    std::vector<Vec3d> H[2], B[2], f[2];
    for (int b = 0; b < 2; ++b) {
      H[b].resize(g.nodeCount());
      B[b].resize(g.nodeCount());
      f[b].resize(g.nodeCount());
      EXPECT_EQ(magneticForce(g, paperLaw(), in, {H[b].data(), B[b].data(), f[b].data()},
                              b == 0 ? Backend::Cpu : Backend::Cuda),
                b == 0 ? Backend::Cpu : Backend::Cuda);
    }
    EXPECT_LT(relativeDifference(H[1], H[0]), kParity) << "H, mask " << mask;
    EXPECT_LT(relativeDifference(B[1], B[0]), kParity) << "B, mask " << mask;
    EXPECT_LT(relativeDifference(f[1], f[0]), 1e-10) << "force, mask " << mask;
  }
}
