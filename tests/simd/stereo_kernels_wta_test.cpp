// Winner-take-all and finalizeRow kernels of every available backend against the scalar
// reference (the StereoKernelsTest suite, instantiated in stereo_kernels_test.cpp), and the
// reference against what WtaRowState documents.
#include <gtest/gtest.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <vector>


#include "simd/stereo_kernels.hpp"
#include "stereo_kernels_test_support.hpp"

namespace svslam::simd {
namespace {

using namespace test_support;

// num_disp aggregated planes at an odd stride, preceded by the 0xFFFF row of plane -1. A few
// columns are forced all-0xFFFF or all-equal (ties on every plane) whatever the distribution.
std::vector<std::uint16_t> randomPlanes(int width, int num_disp, std::ptrdiff_t stride,
                                        std::mt19937& rng, Dist dist) {
  auto c = randomU16(static_cast<std::size_t>(num_disp * stride + width), rng, dist);
  std::fill(c.begin(), c.begin() + stride, std::uint16_t{0xFFFF});
  for (int x = 0; x < width; x += 5) {
    const std::uint16_t v = (x % 10 == 0) ? std::uint16_t{0xFFFF} : drawU16(rng, dist);
    for (int i = 0; i < num_disp; ++i) c[static_cast<std::size_t>((i + 1) * stride + x)] = v;
  }
  return c;
}

// A whole row as the dense stage runs it: wtaInitRow, then every plane in blocks of varying
// size; the state is compared after every block.
TEST_P(StereoKernelsTest, WtaUpdateRowsMatchesScalarOverWholeRows) {
  std::mt19937 rng(31337);
  const int schedules[][4] = {{1000, 0, 0, 0}, {1, 1, 1, 1}, {3, 7, 1, 16}, {16, 5, 2, 9}};
  for (int width : kWidths) {
    for (int num_disp : kNumDisps) {
      for (int d0 : {0, 5, width}) {
        for (Dist dist : kDists) {
          for (const auto& sched : schedules) {
            const std::ptrdiff_t stride = oddStride(width);
            const auto planes = randomPlanes(width, num_disp, stride, rng, dist);
            WtaBuffers got(width), want(width);
            wtaInitRow(got.view(), width);
            wtaInitRow(want.view(), width);
            int step = 0;
            for (int i0 = 0; i0 < num_disp;) {
              const int n = std::min(num_disp - i0, std::max(sched[step++ % 4], 1));
              wtaStep(planes, stride, i0, n, width, d0, got, want,
                      where("wtaUpdateRows", width, num_disp, d0, sched[1], dist));
              if (HasFatalFailure()) return;
              i0 += n;
            }
          }
        }
      }
    }
  }
}

// Arbitrary states and i0 > 0: every branch of the reference from any starting point, bidx at
// i0 - 1 often (the "right neighbour" branch) and -1 often.
TEST_P(StereoKernelsTest, WtaUpdateRowsMatchesScalarFromAnyState) {
  std::mt19937 rng(5150);
  for (int width : kWidths) {
    for (int i0 : {1, 5, 40}) {
      for (int n : {1, 2, 3, 16}) {
        for (Dist dist : kDists) {
          for (int d0 : kD0s) {
            const std::ptrdiff_t stride = oddStride(width);
            auto planes = randomPlanes(width, i0 + n, stride, rng, dist);
            for (int x = 0; x < width; ++x)  // plane i0 - 1, the `prev` row of the first plane
              planes[static_cast<std::size_t>(i0 * stride + x)] = drawU16(rng, dist);
            WtaBuffers got(width);
            for (auto* v :
                 {&got.best, &got.second, &got.cm, &got.cp, &got.pm1, &got.pm2, &got.best_r})
              for (auto& e : *v) e = drawU16(rng, dist);
            for (auto* v : {&got.bidx, &got.idx_r}) {
              for (auto& e : *v) {
                const std::uint32_t r = rng() % 4;
                e = static_cast<std::int16_t>(r == 0   ? -1
                                              : r == 1 ? i0 - 1
                                                       : static_cast<int>(rng() % (i0 + n)));
              }
            }
            WtaBuffers want = got;
            wtaStep(planes, stride, i0, n, width, d0, got, want,
                    where("wtaUpdateRows any state", width, i0, n, d0, dist));
            if (HasFatalFailure()) return;
          }
        }
      }
    }
  }
}

// finalizeRow against the scalar reference: random final WTA states (no candidate, ties,
// 0xFFFF markers, flat and negative parabolas), every filter switched on and off, a texture
// mask or none; outputs compared bit for bit (float bits), counts exactly.
TEST_P(StereoKernelsTest, FinalizeRowMatchesScalar) {
  std::mt19937 rng(4242);
  std::vector<float> sigma_table(301);
  for (auto& v : sigma_table) v = static_cast<float>(rng() % 1000) / 997.0f;
  for (int width : kWidths) {
    for (int num_disp : {1, 3, 16, 64}) {
      for (int d0 : kD0s) {
        for (int variant = 0; variant < 16; ++variant) {
          FinalizeParams p{};
          p.num_disp = num_disp;
          p.d0 = d0;
          p.uniqueness_pct = (variant & 1) ? 10 : 0;
          p.lr_check = (variant & 2) != 0;
          p.lr_max_diff = (variant & 4) ? 1 : 0;
          p.subpixel = (variant & 8) != 0;
          p.inv_area = 1.0f / 81.0f;
          p.sigma_by_denom = sigma_table.data();
          p.max_denom = static_cast<int>(sigma_table.size()) - 1;
          WtaBuffers st(width);
          st.idx_r.resize(static_cast<std::size_t>(width) + 1);  // readable at [0, width + 1)
          const auto draw_idx = [&]() {
            const std::uint32_t r = rng() % 8;
            return static_cast<std::int16_t>(r == 0 ? -1 : static_cast<int>(rng() % num_disp));
          };
          for (int x = 0; x < width; ++x) {
            const std::size_t ux = static_cast<std::size_t>(x);
            st.bidx[ux] = draw_idx();
            st.best[ux] = static_cast<std::uint16_t>(rng() % 200);
            const std::uint32_t r = rng();
            st.second[ux] = (r % 7 == 0) ? std::uint16_t{0xFFFF}
                                         : static_cast<std::uint16_t>(st.best[ux] + r % 40);
            st.cm[ux] = (r % 5 == 0) ? std::uint16_t{0xFFFF}
                                     : static_cast<std::uint16_t>(st.best[ux] + (r >> 8) % 200);
            st.cp[ux] = (r % 11 == 0) ? std::uint16_t{0xFFFF}
                                      : static_cast<std::uint16_t>(rng() % 400);
          }
          for (auto& e : st.idx_r) e = draw_idx();
          std::vector<std::uint8_t> tex(static_cast<std::size_t>(width));
          for (auto& e : tex) e = static_cast<std::uint8_t>(rng() % 5 == 0);
          const std::uint8_t* low = (variant % 3 == 0) ? tex.data() : nullptr;
          const std::size_t n = static_cast<std::size_t>(width);
          std::vector<float> gd(n), gs(n), gc(n), wd(n), ws(n), wc(n);
          FinalizeCounts gcnt, wcnt;
          gcnt.valid = wcnt.valid = 7;  // counts are incremented, not reset
          k_->finalizeRow(st.view(), low, width, p, gd.data(), gs.data(), gc.data(), gcnt);
          ref_->finalizeRow(st.view(), low, width, p, wd.data(), ws.data(), wc.data(), wcnt);
          const std::string ctx = where("finalizeRow", width, num_disp, d0, variant, Dist::kFull);
          for (std::size_t x = 0; x < n; ++x) {
            ASSERT_EQ(std::memcmp(&gd[x], &wd[x], sizeof(float)), 0)
                << ctx << " disp x=" << x << " " << gd[x] << " vs " << wd[x];
            ASSERT_EQ(std::memcmp(&gs[x], &ws[x], sizeof(float)), 0) << ctx << " sigma x=" << x;
            ASSERT_EQ(std::memcmp(&gc[x], &wc[x], sizeof(float)), 0) << ctx << " curv x=" << x;
          }
          EXPECT_EQ(gcnt.no_candidate, wcnt.no_candidate) << ctx;
          EXPECT_EQ(gcnt.low_texture, wcnt.low_texture) << ctx;
          EXPECT_EQ(gcnt.not_unique, wcnt.not_unique) << ctx;
          EXPECT_EQ(gcnt.lr_inconsistent, wcnt.lr_inconsistent) << ctx;
          EXPECT_EQ(gcnt.valid, wcnt.valid) << ctx;
          EXPECT_EQ(wcnt.no_candidate + wcnt.low_texture + wcnt.not_unique +
                        wcnt.lr_inconsistent + wcnt.valid,
                    width + 7)
              << ctx;
        }
      }
    }
  }
}

// wtaNeighbours against the scalar reference: random planes (some 0xFFFF), bidx anywhere in
// [-1, num_disp), rows allocated with exactly the documented readable range.
TEST_P(StereoKernelsTest, WtaNeighboursMatchesScalar) {
  std::mt19937 rng(8080);
  for (int width : kWidths) {
    for (int num_disp : {1, 2, 3, 16, 65}) {
      for (Dist dist : kDists) {
        const std::ptrdiff_t stride = oddStride(width);
        std::vector<std::uint16_t> planes(
            static_cast<std::size_t>((num_disp - 1) * stride + width + 1));
        for (auto& v : planes) v = drawU16(rng, dist);
        WtaBuffers got(width);
        for (auto& b : got.bidx) b = static_cast<std::int16_t>(static_cast<int>(rng() % (num_disp + 1)) - 1);
        for (auto* v : {&got.cm, &got.cp})
          for (auto& e : *v) e = drawU16(rng, Dist::kFull);
        WtaBuffers want = got;
        k_->wtaNeighbours(planes.data(), stride, num_disp, width, got.view());
        ref_->wtaNeighbours(planes.data(), stride, num_disp, width, want.view());
        ASSERT_EQ(got.cm, want.cm) << where("wtaNeighbours cm", width, num_disp, 0, 0, dist);
        ASSERT_EQ(got.cp, want.cp) << where("wtaNeighbours cp", width, num_disp, 0, 0, dist);
      }
    }
  }
}

// wtaInitRow is shared by all backends; checked here once per backend run for simplicity.
TEST_P(StereoKernelsTest, WtaInitRowSetsTheDocumentedStart) {
  WtaBuffers b(33);
  for (auto* v : {&b.best, &b.second, &b.cm, &b.cp, &b.pm1, &b.pm2, &b.best_r})
    std::fill(v->begin(), v->end(), std::uint16_t{3});
  std::fill(b.bidx.begin(), b.bidx.end(), std::int16_t{3});
  std::fill(b.idx_r.begin(), b.idx_r.end(), std::int16_t{3});
  wtaInitRow(b.view(), 33);
  for (auto* v : {&b.best, &b.second, &b.cm, &b.cp, &b.pm1, &b.pm2, &b.best_r})
    EXPECT_EQ(*v, std::vector<std::uint16_t>(33, 0xFFFF));
  EXPECT_EQ(b.bidx, std::vector<std::int16_t>(33, -1));
  EXPECT_EQ(b.idx_r, std::vector<std::int16_t>(33, -1));
}

// The scalar reference itself against the meaning WtaRowState documents, computed directly
// from all planes at once (the streaming form must not drift from it).
TEST(ScalarReference, WtaUpdateRowsMeansWhatWtaRowStateDocuments) {
  std::mt19937 rng(2718);
  for (int width : {1, 7, 33, 127}) {
    for (int num_disp : kNumDisps) {
      for (int d0 : kD0s) {
        for (Dist dist : kDists) {
          const std::ptrdiff_t stride = oddStride(width);
          const auto planes = randomPlanes(width, num_disp, stride, rng, dist);
          const auto agg = [&](int i, int x) {
            return planes[static_cast<std::size_t>((i + 1) * stride + x)];
          };
          WtaBuffers s(width);
          wtaInitRow(s.view(), width);
          scalarKernels().wtaUpdateRows(planes.data() + stride, stride, num_disp, 0, width, d0,
                                        s.view());
          const std::string ctx = where("definition", width, num_disp, d0, 0, dist);
          for (int x = 0; x < width; ++x) {
            std::uint16_t best = 0xFFFF;
            int bidx = -1;
            for (int i = 0; i < num_disp; ++i) {
              if (agg(i, x) < best) {
                best = agg(i, x);
                bidx = i;
              }
            }
            std::uint16_t second = 0xFFFF;
            for (int i = 0; i < num_disp; ++i)
              if (std::abs(i - bidx) > 1) second = std::min(second, agg(i, x));
            const std::uint16_t cm = bidx >= 1 ? agg(bidx - 1, x) : std::uint16_t{0xFFFF};
            const std::uint16_t cp =
                bidx >= 0 && bidx + 1 < num_disp ? agg(bidx + 1, x) : std::uint16_t{0xFFFF};
            ASSERT_EQ(s.best[static_cast<std::size_t>(x)], best) << ctx << " x=" << x;
            ASSERT_EQ(s.bidx[static_cast<std::size_t>(x)], bidx) << ctx << " x=" << x;
            ASSERT_EQ(s.second[static_cast<std::size_t>(x)], second) << ctx << " x=" << x;
            ASSERT_EQ(s.cm[static_cast<std::size_t>(x)], cm) << ctx << " x=" << x;
            ASSERT_EQ(s.cp[static_cast<std::size_t>(x)], cp) << ctx << " x=" << x;
            WtaBuffers n = s;  // the stored-plane form gives the same neighbours
            n.cm.assign(n.cm.size(), 0x1234);
            n.cp.assign(n.cp.size(), 0x1234);
            wtaNeighboursRange(planes.data() + stride, stride, num_disp, x, x + 1, n.view());
            ASSERT_EQ(n.cm[static_cast<std::size_t>(x)], cm) << ctx << " x=" << x;
            ASSERT_EQ(n.cp[static_cast<std::size_t>(x)], cp) << ctx << " x=" << x;
            std::uint16_t best_r = 0xFFFF;
            int idx_r = -1;
            for (int i = 0; i < num_disp && x + d0 + i < width; ++i) {
              if (agg(i, x + d0 + i) < best_r) {
                best_r = agg(i, x + d0 + i);
                idx_r = i;
              }
            }
            ASSERT_EQ(s.best_r[static_cast<std::size_t>(x)], best_r) << ctx << " xr=" << x;
            ASSERT_EQ(s.idx_r[static_cast<std::size_t>(x)], idx_r) << ctx << " xr=" << x;
          }
        }
      }
    }
  }
}

}  // namespace
}  // namespace svslam::simd
