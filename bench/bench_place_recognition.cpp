// Place recognition cost: BinaryVocabulary::transform and PlaceDatabase::query on synthetic
// descriptors, one thread.
//
// Data: 1200 "places", each 300 random 256-bit prototypes; a keyframe of a place holds noisy
// copies (26 random bits of 256 flipped, ~10 %) of a random 70 % of them (~210 descriptors). The
// vocabulary (k = 10, L = 5, seed 7) is trained once on the prototypes, one "image" per place.
// A database of K keyframes holds 5 consecutive keyframes per place (places 0 .. K/5 - 1).
//   BM_Transform500      transform of 500 descriptors (noisy copies of random prototypes).
//   BM_Query/K           one query (id K, every keyframe eligible) with a fresh keyframe of a
//                        random stored place; counters: touched = keyframes read through the
//                        inverted lists, entries = list entries read, bytes_per_keyframe =
//                        memoryBytes() / K, add_us = mean add() time while building.
//   BM_BruteForce/K      the same query answered by scoring every stored keyframe (the cost an
//                        inverted index avoids), for comparison.
// After the benchmarks the program prints the query time ratio 5000 / 1000 (linear growth = 5).
// Run: build/bench/bench_place_recognition
#include <benchmark/benchmark.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <map>
#include <memory>
#include <random>
#include <vector>

#include "loop/binary_vocabulary.hpp"
#include "loop/place_database.hpp"

namespace {

using svslam::BinaryVocabulary;
using svslam::BowVector;
using svslam::OrbDescriptor;
using svslam::PlaceCandidate;
using svslam::PlaceDatabase;
using svslam::PlaceDatabaseParams;

constexpr int kPlaces = 1200, kPrototypes = 300, kPerPlace = 5;

OrbDescriptor randomDescriptor(std::mt19937_64& rng) {
  OrbDescriptor d;
  for (auto& w : d.words) w = rng();
  return d;
}

OrbDescriptor noisyCopy(OrbDescriptor d, std::mt19937_64& rng) {
  for (int f = 0; f < 26; ++f) {
    const auto bit = rng() % 256;
    d.words[bit / 64] ^= std::uint64_t{1} << (bit % 64);
  }
  return d;
}

struct World {
  std::vector<std::vector<OrbDescriptor>> places;
  std::unique_ptr<BinaryVocabulary> voc;
};

const World& world() {
  static const World w = [] {
    World out;
    std::mt19937_64 rng(1);
    out.places.resize(kPlaces);
    for (auto& p : out.places)
      for (int i = 0; i < kPrototypes; ++i) p.push_back(randomDescriptor(rng));
    svslam::VocabularyParams vp;
    vp.depth = 5;
    const auto t0 = std::chrono::steady_clock::now();
    auto voc = BinaryVocabulary::train(out.places, vp);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (!voc) std::abort();
    std::printf("vocabulary k=10 L=5: %d words, trained in %.1f s on %d descriptors\n",
                voc->numWords(), s, kPlaces * kPrototypes);
    out.voc = std::make_unique<BinaryVocabulary>(std::move(voc).value());
    return out;
  }();
  return w;
}

std::vector<OrbDescriptor> keyframeOf(int place, std::mt19937_64& rng) {
  std::vector<OrbDescriptor> out;
  for (const auto& p : world().places[static_cast<std::size_t>(place)])
    if (rng() % 10 < 7) out.push_back(noisyCopy(p, rng));
  return out;
}

struct Db {
  std::unique_ptr<PlaceDatabase> db;
  std::vector<BowVector> vectors;
  double add_us = 0;
};

Db& database(int k) {
  static std::map<int, Db> cache;
  auto it = cache.find(k);
  if (it != cache.end()) return it->second;
  Db& d = cache[k];
  d.db = std::make_unique<PlaceDatabase>(PlaceDatabaseParams{}, static_cast<std::size_t>(k),
                                         static_cast<std::size_t>(world().voc->numWords()));
  std::mt19937_64 rng(2);
  d.vectors.resize(static_cast<std::size_t>(k));
  for (int i = 0; i < k; ++i) world().voc->transform(keyframeOf(i / kPerPlace, rng), d.vectors[i]);
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < k; ++i)
    if (!d.db->add(i, d.vectors[static_cast<std::size_t>(i)])) std::abort();
  d.add_us =
      std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count() / k;
  return d;
}

// Query vectors: fresh keyframes of stored places; the previous keyframe (id K - 1) is replaced
// in the prior by a same-place keyframe so that the query is not skipped.
std::vector<BowVector> queries(int k, int n) {
  std::mt19937_64 rng(3);
  std::vector<BowVector> q(static_cast<std::size_t>(n));
  for (auto& v : q) world().voc->transform(keyframeOf((k - 1) / kPerPlace, rng), v);
  return q;
}

void BM_Transform500(benchmark::State& state) {
  std::mt19937_64 rng(4);
  std::vector<OrbDescriptor> desc;
  for (int i = 0; i < 500; ++i)
    desc.push_back(noisyCopy(world().places[rng() % kPlaces][rng() % kPrototypes], rng));
  BowVector out;
  for (auto _ : state) {
    world().voc->transform(desc, out);
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(state.iterations() * 500);
}
BENCHMARK(BM_Transform500);

void BM_Query(benchmark::State& state) {
  const int k = static_cast<int>(state.range(0));
  Db& d = database(k);
  const auto q = queries(k, 64);
  std::vector<PlaceCandidate> out;
  std::size_t i = 0, entries = 0, touched = 0, n = 0;
  for (auto _ : state) {
    if (!d.db->query(q[i++ % q.size()], k, out)) state.SkipWithError("query failed");
    entries += d.db->lastQueryStats().entries_read;
    touched += static_cast<std::size_t>(d.db->lastQueryStats().last_query_touched);
    ++n;
  }
  state.counters["touched"] = static_cast<double>(touched) / static_cast<double>(n);
  state.counters["entries"] = static_cast<double>(entries) / static_cast<double>(n);
  state.counters["bytes_per_keyframe"] = static_cast<double>(d.db->memoryBytes()) / k;
  state.counters["add_us"] = d.add_us;
}
BENCHMARK(BM_Query)->Arg(1000)->Arg(5000)->Unit(benchmark::kMicrosecond);

void BM_BruteForce(benchmark::State& state) {
  const int k = static_cast<int>(state.range(0));
  Db& d = database(k);
  const auto q = queries(k, 64);
  std::size_t i = 0;
  for (auto _ : state) {
    const BowVector& v = q[i++ % q.size()];
    double best = 0;
    for (const BowVector& s : d.vectors) best = std::max(best, BinaryVocabulary::score(v, s));
    benchmark::DoNotOptimize(best);
  }
}
BENCHMARK(BM_BruteForce)->Arg(1000)->Arg(5000)->Unit(benchmark::kMicrosecond);

double meanQueryUs(int k) {
  Db& d = database(k);
  const auto q = queries(k, 64);
  std::vector<PlaceCandidate> out;
  const int reps = 2000;
  const auto t0 = std::chrono::steady_clock::now();
  for (int r = 0; r < reps; ++r)
    if (!d.db->query(q[static_cast<std::size_t>(r) % q.size()], k, out)) std::abort();
  return std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count() /
         reps;
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  const double t1 = meanQueryUs(1000), t5 = meanQueryUs(5000);
  std::printf(
      "query: %.1f us at 1000 keyframes, %.1f us at 5000, ratio 5000/1000 = %.2f "
      "(linear = 5)\n",
      t1, t5, t5 / t1);
  return 0;
}
