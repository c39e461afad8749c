// PlaceDatabase::query and BinaryVocabulary::transform allocate nothing once warm, counted by
// replacing the global operator new in this test executable.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <cstdlib>
#include <new>
#include <random>
#include <vector>

#include "loop/binary_vocabulary.hpp"
#include "loop/place_database.hpp"
#include "loop_test_support.hpp"

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define SVSLAM_COUNT_ALLOCATIONS 0  // the sanitizers own operator new: counting is skipped
#else
#define SVSLAM_COUNT_ALLOCATIONS 1
#endif

namespace {
std::atomic<std::int64_t> g_allocations{0};
}  // namespace

#if SVSLAM_COUNT_ALLOCATIONS
// The replacements pair operator new with malloc and operator delete with free; GCC's
// -Wmismatched-new-delete cannot see that pairing once new is inlined (false positive at -O2).
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void* operator new(std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
#endif

namespace svslam {
namespace {

using namespace loop_test;  // NOLINT: the shared fixtures

TEST(PlaceDatabaseAllocations, QueryAndTransformAllocateNothingOnceWarm) {
  if (!SVSLAM_COUNT_ALLOCATIONS) GTEST_SKIP() << "allocation counting is off under sanitizers";
  std::mt19937_64 rng(12);
  std::vector<std::vector<OrbDescriptor>> places;
  for (int p = 0; p < 30; ++p) places.push_back(randomDescriptors(80, rng));
  auto voc = BinaryVocabulary::train(places, VocabularyParams{});
  ASSERT_TRUE(voc.isOk());
  std::vector<std::vector<OrbDescriptor>> frames;
  for (int i = 0; i < 150; ++i)
    frames.push_back(keyframeOf(places[static_cast<std::size_t>(i / 5)], 0.7, 0.1, rng));
  for (int p = 2; p < 6; ++p)  // a revisit, so that candidates are produced
    for (int k = 0; k < 5; ++k)
      frames.push_back(keyframeOf(places[static_cast<std::size_t>(p)], 0.7, 0.1, rng));

  PlaceDatabase db(PlaceDatabaseParams{}, frames.size(), static_cast<std::size_t>(voc->numWords()));
  BowVector v;
  v.reserve(1000);
  std::vector<PlaceCandidate> out;
  out.reserve(16);
  std::vector<BowVector> vectors(frames.size());
  for (std::size_t i = 0; i < frames.size(); ++i) voc->transform(frames[i], vectors[i]);
  std::int64_t query_allocations = 0, transform_allocations = 0;
  int reported = 0;
  for (int i = 0; i < static_cast<int>(frames.size()); ++i) {
    const auto& f = frames[static_cast<std::size_t>(i)];
    std::int64_t before = g_allocations.load();
    voc->transform(f, v);
    transform_allocations += g_allocations.load() - before;
    before = g_allocations.load();
    ASSERT_TRUE(db.query(vectors[static_cast<std::size_t>(i)], i, out).isOk());
    query_allocations += g_allocations.load() - before;
    reported += !out.empty();
    ASSERT_TRUE(db.add(i, vectors[static_cast<std::size_t>(i)]).isOk());
  }
  EXPECT_GT(reported, 0);
  EXPECT_EQ(query_allocations, 0);
  EXPECT_EQ(transform_allocations, 0);
}

}  // namespace
}  // namespace svslam
