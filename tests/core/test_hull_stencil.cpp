// The assembled material rows (HullStencil) against the element-by-element
// product they replace: random cells on a small grid, cells on every face of
// it (where neighbours fall outside the grid), in double and float.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "lodestone/core/field/hull_stencil.h"

using namespace lodestone;

namespace {

struct Cells {
  GridSpec grid;
  std::vector<std::size_t> base;
  std::vector<double> packed;  // 36 per cell: upper triangle of a random symmetric matrix
};

Cells randomCells(unsigned seed, Index3 dims = {9, 7, 6}) {
  Cells c;
  c.grid.dx = 0.01;
  c.grid.dims = dims;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(-1, 1);
  const Index3 cd = c.grid.cellDims();
  for (int k = 0; k < cd.k; ++k)
    for (int j = 0; j < cd.j; ++j)
      for (int i = 0; i < cd.i; ++i) {
        // About half the cells, and every cell of the first and last layers.
        const bool face = i == 0 || j == 0 || k == 0 || i == cd.i - 1 || j == cd.j - 1 || k == cd.k - 1;
        if (face || U(rng) > 0) c.base.push_back(c.grid.index(i, j, k));
      }
  // A shuffled slot order: the stencil must not depend on it.
  std::shuffle(c.base.begin(), c.base.end(), rng);
  c.packed.resize(c.base.size() * 36);
  for (double& v : c.packed) v = U(rng);
  return c;
}

// out += sum over cells of E v at the cell's corners.
void elementProduct(const Cells& c, const double* v, double* out) {
  std::size_t off[8];
  for (int q = 0; q < 8; ++q) off[q] = c.grid.index(q & 1, (q >> 1) & 1, q >> 2);
  for (std::size_t s = 0; s < c.base.size(); ++s) {
    const double* E = &c.packed[s * 36];
    for (int a = 0, e = 0; a < 8; ++a)
      for (int b = a; b < 8; ++b, ++e) {
        out[c.base[s] + off[a]] += E[e] * v[c.base[s] + off[b]];
        if (b != a) out[c.base[s] + off[b]] += E[e] * v[c.base[s] + off[a]];
      }
  }
}

double relativeDifference(const std::vector<double>& a, const std::vector<double>& b) {
  double num = 0, den = 0;
  for (std::size_t m = 0; m < a.size(); ++m) {
    num += (a[m] - b[m]) * (a[m] - b[m]);
    den += b[m] * b[m];
  }
  return std::sqrt(num / den);
}

}  // namespace

TEST(HullStencil, AssembledRowsEqualTheElementProduct) {
  for (unsigned seed : {1u, 2u, 3u}) {
    const Cells c = randomCells(seed, seed == 3 ? Index3{41, 5, 4} : Index3{9, 7, 6});
    HullStencil<double> st;
    st.build(c.grid, c.base.data(), c.base.size());
    st.assemble(c.packed.data());
    const std::size_t n = c.grid.nodeCount();
    std::vector<double> v(n), ref(n, 0.0), got(n, 0.0), diag(n, 0.0), refDiag(n, 0.0), e(n, 0.0);
    std::mt19937 rng(seed + 10);
    std::uniform_real_distribution<double> U(-1, 1);
    for (double& x : v) x = U(rng);
    elementProduct(c, v.data(), ref.data());
    st.addProduct(v.data(), got.data());
    EXPECT_LT(relativeDifference(got, ref), 1e-14) << "seed " << seed;
    // The diagonal is the product with unit vectors, read at their node.
    st.addDiagonal(diag.data());
    for (std::size_t m = 0; m < n; ++m) {
      e[m] = 1.0;
      std::vector<double> col(n, 0.0);
      elementProduct(c, e.data(), col.data());
      refDiag[m] = col[m];
      e[m] = 0.0;
    }
    EXPECT_LT(relativeDifference(diag, refDiag), 1e-14) << "seed " << seed;
  }
}

// Cells i in [i0, i1) of every (j, k) on a 53 x 7 x 6 grid: rows of
// i1 - i0 + 1 nodes.
Cells slabCells(int i0, int i1, unsigned seed) {
  Cells c;
  c.grid.dx = 0.01;
  c.grid.dims = {53, 7, 6};
  const Index3 cd = c.grid.cellDims();
  for (int k = 0; k < cd.k; ++k)
    for (int j = 0; j < cd.j; ++j)
      for (int i = i0; i < i1; ++i) c.base.push_back(c.grid.index(i, j, k));
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(-1, 1);
  c.packed.resize(c.base.size() * 36);
  for (double& v : c.packed) v = U(rng);
  return c;
}

// The block (16, 8 or 4 slots) follows the rows' length: the largest whose
// padding stays within a fifth of the slots that blocks of 4 need. Whole
// blocks go through the block kernel, partial ones lane by lane; both sum a
// node's taps in the same order, so a row split anywhere gives the same bits.
TEST(HullStencil, BlocksFollowTheRowsAndRowsSplitAnywhereGiveTheSameBits) {
  struct Case {
    Cells cells;
    int block;
  };
  const std::vector<Case> cases = {
      {randomCells(5, {53, 7, 6}), 16},  // rows of 53 nodes: 64 slots against 56
      {slabCells(10, 30, 6), 8},         // 21 nodes: 24 slots (16: 32)
      {slabCells(10, 19, 7), 4},         // 10 nodes: 12 slots (8: 16)
      {slabCells(20, 21, 8), 4},         // a sheet one cell thick: 2 nodes, 4 slots (8: 8)
  };
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> U(-1, 1);
  for (const Case& cs : cases) {
    const Cells& c = cs.cells;
    HullStencil<double> st;
    st.build(c.grid, c.base.data(), c.base.size());
    st.assemble(c.packed.data());
    EXPECT_EQ(st.block(), cs.block);
    const std::size_t n = c.grid.nodeCount();
    std::vector<double> v(n), ref(n, 0.0), whole(n, 0.0), split(n, 0.0);
    for (double& x : v) x = U(rng);
    elementProduct(c, v.data(), ref.data());
    st.addProduct(v.data(), whole.data());
    EXPECT_LT(relativeDifference(whole, ref), 1e-14) << "block " << st.block();
    for (int k = 0; k < c.grid.dims.k; ++k)
      for (int j = 0; j < c.grid.dims.j; ++j) {
        const int lo = st.lo(j, k), hi = st.hi(j, k);
        const std::size_t row = c.grid.index(0, j, k);
        // Three pieces cut at random places (empty pieces included).
        std::uniform_int_distribution<int> cut(lo, hi);
        int a = cut(rng), b = cut(rng);
        if (a > b) std::swap(a, b);
        st.addRow(j, k, lo, a, v.data() + row, split.data() + row);
        st.addRow(j, k, a, b, v.data() + row, split.data() + row);
        st.addRow(j, k, b, hi, v.data() + row, split.data() + row);
      }
    for (std::size_t m = 0; m < n; ++m) ASSERT_EQ(split[m], whole[m]) << "block " << st.block() << ", node " << m;
    // The float copy keeps the layout.
    HullStencil<float> f;
    f.assignConverted(st);
    EXPECT_EQ(f.block(), st.block());
    std::vector<float> vf(v.begin(), v.end()), got(n, 0.0f);
    f.addProduct(vf.data(), got.data());
    std::vector<double> gd(got.begin(), got.end());
    EXPECT_LT(relativeDifference(gd, ref), 1e-5) << "block " << st.block();
  }
}

TEST(HullStencil, ScatteredElementsEqualTheGatheredAssembly) {
  const Cells c = randomCells(7);
  HullStencil<double> gathered, scattered;
  gathered.build(c.grid, c.base.data(), c.base.size());
  gathered.assemble(c.packed.data());
  scattered.build(c.grid, c.base.data(), c.base.size());
  scattered.clear();
  // Element by element: E_cd into tap (c -> d) of corner c's node.
  using H = HullStencil<double>;
  for (std::size_t s = 0; s < c.base.size(); ++s)
    for (int a = 0, e = 0; a < 8; ++a)
      for (int b = a; b < 8; ++b, ++e) {
        const double E = c.packed[s * 36 + std::size_t(e)];
        scattered.values()[scattered.at(scattered.corner(s, a), H::tap(a, b))] += E;
        if (b != a) scattered.values()[scattered.at(scattered.corner(s, b), H::tap(b, a))] += E;
      }
  ASSERT_EQ(gathered.size(), scattered.size());
  const std::size_t count = std::size_t(HullStencil<double>::kTaps) * gathered.size();
  double worst = 0;
  for (std::size_t m = 0; m < count; ++m)
    worst = std::max(worst, std::fabs(gathered.values()[m] - scattered.values()[m]));
  EXPECT_LT(worst, 1e-14);
  EXPECT_TRUE(gathered.sameCells(c.grid, c.base.data(), c.base.size()));
  std::vector<std::size_t> other(c.base.begin(), c.base.end() - 1);
  EXPECT_FALSE(gathered.sameCells(c.grid, other.data(), other.size()));
}

TEST(HullStencil, FloatRowsMatchDoubleRowsToSinglePrecision) {
  const Cells c = randomCells(4);
  HullStencil<float> st;
  st.build(c.grid, c.base.data(), c.base.size());
  st.assemble(c.packed.data());
  const std::size_t n = c.grid.nodeCount();
  std::vector<double> v(n), ref(n, 0.0);
  std::vector<float> vf(n), got(n, 0.0f);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> U(-1, 1);
  for (std::size_t m = 0; m < n; ++m) vf[m] = float(v[m] = U(rng));
  elementProduct(c, v.data(), ref.data());
  st.addProduct(vf.data(), got.data());
  std::vector<double> gd(got.begin(), got.end());
  EXPECT_LT(relativeDifference(gd, ref), 1e-5);
  EXPECT_GT(relativeDifference(gd, ref), 0.0);  // it did run in float
  // A float copy of the double rows (the multigrid's fine level) does the same.
  HullStencil<double> d;
  d.build(c.grid, c.base.data(), c.base.size());
  d.assemble(c.packed.data());
  HullStencil<float> copy;
  copy.assignConverted(d);
  std::vector<float> got2(n, 0.0f);
  copy.addProduct(vf.data(), got2.data());
  std::vector<double> gd2(got2.begin(), got2.end());
  EXPECT_LT(relativeDifference(gd2, ref), 1e-5);
}

TEST(HullStencil, RejectsACellOutsideTheGrid) {
  GridSpec g;
  g.dx = 0.01;
  g.dims = {4, 4, 4};
  const std::size_t bad = g.index(3, 1, 1);  // a base node on the last x layer has no cell
  HullStencil<double> st;
  EXPECT_THROW(st.build(g, &bad, 1), InvalidArgument);
}
