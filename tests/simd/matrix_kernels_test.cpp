// The EKF's rank update C -= A B^T (full or lower triangle): the scalar reference against an
// independent (non-fused) Eigen product, and every backend this CPU runs bit for bit against the
// scalar reference, on odd sizes, strides and ranks.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cstring>
#include <random>
#include <vector>

#include "simd/matrix_kernels.hpp"

namespace svslam::simd {
namespace {

struct Case {
  Eigen::MatrixXd C, A, B;  // padded: the kernel sees the top-left rows x cols of C
  int rows = 0, cols = 0, r = 0;
  bool lower = false;
};

Case randomCase(int rows, int cols, int r, bool lower, int pad, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  auto fill = [&](Eigen::MatrixXd& M, int nr, int nc) {
    M.resize(nr, nc);
    for (int j = 0; j < nc; ++j)
      for (int i = 0; i < nr; ++i) M(i, j) = g(rng);
  };
  Case c;
  c.rows = rows;
  c.cols = cols;
  c.r = r;
  c.lower = lower;
  fill(c.C, rows + pad, cols + pad);
  fill(c.A, rows + pad, r);
  fill(c.B, cols + 2 * pad, r);
  return c;
}

void run(const MatrixKernels& k, Case& c) {
  std::vector<double> ws(rankUpdateWorkspace(c.rows, c.cols, c.r) + 1, -7.0);
  k.rankUpdate(c.C.data(), c.C.outerStride(), c.A.data(), c.A.outerStride(), c.B.data(),
               c.B.outerStride(), c.rows, c.cols, c.r, c.lower, 0, ws.data());
}

bool sameBits(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return a.rows() == b.rows() && a.cols() == b.cols() &&
         std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<std::size_t>(a.size())) ==
             0;
}

TEST(MatrixKernels, ScalarMatchesEigenInsideAndLeavesTheRestAlone) {
  struct Shape {
    int rows, cols, r;
    bool lower;
  };
  for (const Shape& s : {Shape{1, 1, 1, true}, Shape{7, 7, 3, true}, Shape{50, 50, 18, true},
                         Shape{97, 97, 61, true}, Shape{9, 4, 5, false}, Shape{40, 13, 13, false},
                         Shape{5, 30, 2, false}}) {
    Case c = randomCase(s.rows, s.cols, s.r, s.lower, 3, static_cast<unsigned>(s.rows * 1000 + s.r));
    const Eigen::MatrixXd before = c.C;
    const Eigen::MatrixXd product = c.A.topRows(s.rows) * c.B.topRows(s.cols).transpose();
    run(scalarMatrixKernels(), c);
    for (int j = 0; j < c.C.cols(); ++j)
      for (int i = 0; i < c.C.rows(); ++i) {
        if (i < s.rows && j < s.cols && (!s.lower || j <= i))
          EXPECT_NEAR(c.C(i, j), before(i, j) - product(i, j), 1e-12 * (1 + s.r))
              << s.rows << "x" << s.cols << " r " << s.r << " at " << i << "," << j;
        else
          EXPECT_EQ(c.C(i, j), before(i, j)) << "touched outside at " << i << "," << j;
      }
  }
}

TEST(MatrixKernels, EveryAvailableBackendIsBitExactWithScalar) {
  int tested = 0;
  for (Backend b : {Backend::kAvx2, Backend::kAvx512, Backend::kNeon}) {
    if (!matrixBackendAvailable(b)) continue;
    const MatrixKernels& k = matrixKernels(b);
    ASSERT_EQ(k.backend, b);
    ++tested;
    for (bool lower : {true, false})
      for (int n : {1, 3, 4, 11, 12, 13, 25, 64, 97, 130, 300})
        for (int r : {1, 2, 5, 30, 90}) {
          const int pad = (n + r) % 5, cols = lower ? n : (n * 7) % 41 + 1;
          Case ref = randomCase(n, cols, r, lower, pad, static_cast<unsigned>(7 * n + r));
          Case simd = ref;
          run(scalarMatrixKernels(), ref);
          run(k, simd);
          ASSERT_TRUE(sameBits(ref.C, simd.C))
              << k.name << " differs from scalar at " << n << "x" << cols << ", r = " << r
              << (lower ? " (lower)" : "");
        }
  }
  if (tested == 0) GTEST_SKIP() << "no SIMD matrix backend runs on this CPU; scalar only";
}

TEST(MatrixKernels, LargeUpdateCrossesColumnChunksBitExactly) {
  // n = 700 spans several column chunks of the tiled driver.
  if (matrixKernels().backend == Backend::kScalar) GTEST_SKIP() << "no SIMD matrix backend here";
  for (bool lower : {true, false}) {
    Case ref = randomCase(700, lower ? 700 : 333, 37, lower, 1, 99), simd = ref;
    run(scalarMatrixKernels(), ref);
    run(matrixKernels(), simd);
    EXPECT_TRUE(sameBits(ref.C, simd.C)) << (lower ? "lower" : "full");
  }
}

TEST(MatrixKernels, RowPiecesOfATriangleGiveTheSameBitsAsTheWhole) {
  // How EkfSlam splits the triangle among threads: rows [r0, r1) with row0 = r0, columns up to
  // r1, each piece with its own workspace.
  for (const MatrixKernels* k : {&scalarMatrixKernels(), &matrixKernels()}) {
    const int n = 157, r = 19;
    Case whole = randomCase(n, n, r, true, 2, 5);
    Eigen::MatrixXd pieces = whole.C;
    run(*k, whole);
    for (const auto& [r0, r1] : {std::pair{0, 50}, {50, 51}, {51, 111}, {111, 157}}) {
      std::vector<double> ws(rankUpdateWorkspace(r1 - r0, r1, r));
      k->rankUpdate(&pieces(r0, 0), pieces.outerStride(), &whole.A(r0, 0), whole.A.outerStride(),
                    whole.B.data(), whole.B.outerStride(), r1 - r0, r1, r, true, r0, ws.data());
    }
    EXPECT_TRUE(sameBits(whole.C, pieces)) << k->name;
  }
}

TEST(MatrixKernels, EmptySizesDoNothing) {
  Case c = randomCase(4, 4, 3, true, 0, 1);
  const Eigen::MatrixXd before = c.C;
  for (const MatrixKernels* k : {&scalarMatrixKernels(), &matrixKernels()}) {
    k->rankUpdate(c.C.data(), 4, c.A.data(), 4, c.B.data(), 4, 0, 4, 3, true, 0, nullptr);
    k->rankUpdate(c.C.data(), 4, c.A.data(), 4, c.B.data(), 4, 4, 0, 3, false, 0, nullptr);
    k->rankUpdate(c.C.data(), 4, c.A.data(), 4, c.B.data(), 4, 4, 4, 0, true, 0, nullptr);
  }
  EXPECT_EQ(c.C, before);
  EXPECT_EQ(rankUpdateWorkspace(0, 3, 5), 0u);
}

}  // namespace
}  // namespace svslam::simd
