// Per-kernel benchmarks of the stereo row kernels, every available backend, one 640-pixel row
// (items = pixels or pixel-disparity pairs processed).
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "core/aligned_buffer.hpp"
#include "simd/stereo_kernels.hpp"

namespace {

using svslam::AlignedBuffer;
namespace simd = svslam::simd;

constexpr int kW = 640;

template <class T>
void fillRandom(AlignedBuffer<T>& b, unsigned seed, unsigned max) {
  std::mt19937 rng(seed);
  for (std::size_t i = 0; i < b.size(); ++i) b[i] = static_cast<T>(rng() % max);
}

const simd::StereoKernels* kernelsOrSkip(benchmark::State& st) {
  const auto b = static_cast<simd::Backend>(st.range(0));
  if (!simd::backendAvailable(b)) {
    st.SkipWithError("backend not available");
    return nullptr;
  }
  st.SetLabel(simd::backendName(b));
  return &simd::kernels(b);
}

void BM_CensusRow(benchmark::State& st) {
  const auto* k = kernelsOrSkip(st);
  if (!k) return;
  AlignedBuffer<std::uint8_t> img(static_cast<std::size_t>((kW + 16) * 8));
  fillRandom(img, 1, 256);
  AlignedBuffer<std::uint64_t> out(kW);
  for (auto _ : st) {
    k->censusRow(img.data(), kW + 16, kW, 9, 7, out.data());
    benchmark::ClobberMemory();
  }
  st.SetItemsProcessed(st.iterations() * kW);
}

void BM_CensusCostPlanes(benchmark::State& st) {
  const auto* k = kernelsOrSkip(st);
  if (!k) return;
  AlignedBuffer<std::uint64_t> l(kW + 64), r(kW + 64);
  fillRandom(l, 2, 1u << 31);
  fillRandom(r, 3, 1u << 31);
  AlignedBuffer<std::uint8_t> cost(kW);
  for (auto _ : st) {
    for (int d = 0; d < 64; ++d) k->censusCostRow(l.data() + 64, r.data() + 64, kW, d, cost.data());
    benchmark::ClobberMemory();
  }
  st.SetItemsProcessed(st.iterations() * kW * 64);
}

// Byte-plane census layout (backends that have it): the census row, and all 64 cost planes of a
// row in one call.
void BM_CensusPlanesRow(benchmark::State& st) {
  const auto* k = kernelsOrSkip(st);
  if (!k) return;
  if (k->censusPlanesRow == nullptr) {
    st.SkipWithError("no byte-plane census in this backend");
    return;
  }
  AlignedBuffer<std::uint8_t> img(static_cast<std::size_t>((kW + 16) * 8));
  fillRandom(img, 1, 256);
  AlignedBuffer<std::uint8_t> out(static_cast<std::size_t>(8 * kW));
  for (auto _ : st) {
    k->censusPlanesRow(img.data(), kW + 16, kW, 9, 7, out.data(), kW);
    benchmark::ClobberMemory();
  }
  st.SetItemsProcessed(st.iterations() * kW);
}

void BM_CensusPlanesCost64(benchmark::State& st) {
  const auto* k = kernelsOrSkip(st);
  if (!k) return;
  if (k->censusPlanesCostRows == nullptr) {
    st.SkipWithError("no byte-plane census in this backend");
    return;
  }
  const std::ptrdiff_t ps = kW + 64;  // plane stride, x = 0 at 64
  AlignedBuffer<std::uint8_t> l(static_cast<std::size_t>(8 * ps)), r(l.size());
  fillRandom(l, 2, 256);
  fillRandom(r, 3, 256);
  AlignedBuffer<std::uint8_t> cost(static_cast<std::size_t>(64 * kW));
  for (auto _ : st) {
    k->censusPlanesCostRows(l.data() + 64, r.data() + 64, ps, 8, kW, 0, 64, cost.data(), kW);
    benchmark::ClobberMemory();
  }
  st.SetItemsProcessed(st.iterations() * kW * 64);
}

void BM_AddSubBoxPlanes(benchmark::State& st) {
  const auto* k = kernelsOrSkip(st);
  if (!k) return;
  AlignedBuffer<std::uint16_t> col(static_cast<std::size_t>(64 * (kW + 64))), agg(kW);
  AlignedBuffer<std::uint8_t> a(kW), b(kW);
  fillRandom(a, 4, 60);
  fillRandom(b, 5, 60);
  for (auto _ : st) {
    for (int d = 0; d < 64; ++d) {
      std::uint16_t* c = col.data() + d * (kW + 64);
      k->addSubRow(c + 32, a.data(), b.data(), kW);
      k->boxRow(c + 28, kW, 9, agg.data());
    }
    benchmark::ClobberMemory();
  }
  st.SetItemsProcessed(st.iterations() * kW * 64);
}

// range(1) = 0: left and right WTA; 1: left only (d0 = width leaves no right-image candidate).
void BM_WtaPlanes(benchmark::State& st) {
  const auto* k = kernelsOrSkip(st);
  if (!k) return;
  const std::ptrdiff_t stride = kW;
  AlignedBuffer<std::uint16_t> agg(static_cast<std::size_t>(65 * kW));
  fillRandom(agg, 6, 5000);
  std::vector<AlignedBuffer<std::uint16_t>> u(7);
  for (auto& b : u) b.resize(kW);
  AlignedBuffer<std::int16_t> bidx(kW), idx_r(kW);
  const simd::WtaRowState s{u[0].data(), bidx.data(), u[1].data(), u[2].data(), u[3].data(),
                            u[4].data(), u[5].data(), u[6].data(), idx_r.data()};
  for (auto _ : st) {
    simd::wtaInitRow(s, kW);
    for (int i0 = 0; i0 < 64; i0 += 16)
      k->wtaUpdateRows(agg.data() + (i0 + 1) * stride, stride, 16, i0, kW, 0, s);
    benchmark::ClobberMemory();
  }
  st.SetItemsProcessed(st.iterations() * kW * 64);
}

void backends(benchmark::internal::Benchmark* b) {
  for (auto be :
       {simd::Backend::kScalar, simd::Backend::kAvx2, simd::Backend::kAvx512, simd::Backend::kNeon})
    b->Arg(static_cast<int>(be));
  b->ArgName("backend");
}

BENCHMARK(BM_CensusRow)->Apply(backends);
BENCHMARK(BM_CensusCostPlanes)->Apply(backends);
BENCHMARK(BM_CensusPlanesRow)->Apply(backends);
BENCHMARK(BM_CensusPlanesCost64)->Apply(backends);
BENCHMARK(BM_AddSubBoxPlanes)->Apply(backends);
BENCHMARK(BM_WtaPlanes)->Apply([](benchmark::internal::Benchmark* b) {
  for (auto be : {simd::Backend::kScalar, simd::Backend::kAvx2, simd::Backend::kAvx512, simd::Backend::kNeon})
    for (int left_only : {0, 1}) b->Args({static_cast<int>(be), left_only});
  b->ArgNames({"backend", "left_only"});
});

}  // namespace

BENCHMARK_MAIN();
