// PlaceDatabase on a synthetic route of "places" (each a set of random prototype descriptors;
// each keyframe of a place holds noisy copies of a subset): a revisit is found once temporal
// consistency is reached, new places never match, recent keyframes are excluded, a query reads
// only keyframes sharing a word with it.
#include "loop/place_database.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <random>
#include <vector>

#include "loop/binary_vocabulary.hpp"
#include "loop_test_support.hpp"

namespace svslam {
namespace {

using namespace loop_test;  // NOLINT: the shared fixtures

constexpr int kPlaces = 60, kPrototypes = 60, kKeyframesPerPlace = 5;

struct World {
  std::vector<std::vector<OrbDescriptor>> places;  // prototypes per place
  BinaryVocabulary voc;
};

World makeWorld() {
  std::mt19937_64 rng(2024);
  std::vector<std::vector<OrbDescriptor>> places;
  for (int p = 0; p < kPlaces; ++p) places.push_back(randomDescriptors(kPrototypes, rng));
  auto voc = BinaryVocabulary::train(places, VocabularyParams{});  // one "image" per place
  EXPECT_TRUE(voc.isOk());
  return {places, std::move(voc).value()};
}

const World& world() {
  static const World w = makeWorld();
  return w;
}

// The route as a list of place indices, kKeyframesPerPlace keyframes each.
std::vector<BowVector> route(const std::vector<int>& place_order, std::mt19937_64& rng) {
  std::vector<BowVector> out;
  for (int p : place_order)
    for (int k = 0; k < kKeyframesPerPlace; ++k) {
      out.emplace_back();
      world().voc.transform(keyframeOf(world().places[static_cast<std::size_t>(p)], 0.7, 0.1, rng),
                            out.back());
    }
  return out;
}

TEST(PlaceDatabase, BadArguments) {
  PlaceDatabaseParams p;
  p.island_span = 0;
  EXPECT_FALSE(PlaceDatabase(p).initStatus().isOk());
  PlaceDatabase db{PlaceDatabaseParams{}};
  ASSERT_TRUE(db.initStatus().isOk());
  EXPECT_EQ(db.add(1, {}).code(), StatusCode::kInvalidArgument);  // ids start at 0
  EXPECT_EQ(db.add(0, {{3, 0.5f}, {2, 0.5f}}).code(), StatusCode::kInvalidArgument);  // unsorted
  EXPECT_EQ(db.add(0, {{3, -1.0f}}).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(db.add(0, {{0xFFFFFFF0u, 1.0f}}).code(), StatusCode::kInvalidArgument);
  PlaceDatabase small(PlaceDatabaseParams{}, 0, 10);
  EXPECT_EQ(small.add(0, {{10, 1.0f}}).code(), StatusCode::kInvalidArgument);
  EXPECT_TRUE(small.add(0, {{9, 1.0f}}).isOk());
  ASSERT_TRUE(db.add(0, {{3, 1.0f}}).isOk());
  std::vector<PlaceCandidate> out;
  EXPECT_EQ(db.query({{3, 1.0f}}, -1, out).code(), StatusCode::kInvalidArgument);
  ASSERT_TRUE(db.query({{3, 1.0f}}, 0, out).isOk());  // no previous keyframe: skipped
  EXPECT_TRUE(db.lastQueryStats().skipped);
  EXPECT_TRUE(out.empty());
}

TEST(PlaceDatabase, RevisitAfterFiftyPlacesIsFoundOnlyOnceConsistent) {
  std::mt19937_64 rng(7);
  std::vector<int> order;
  for (int p = 0; p < 54; ++p) order.push_back(p);  // places 4..53: 50 places after place 3
  order.push_back(3);
  for (int p = 54; p < kPlaces; ++p) order.push_back(p);  // never seen before
  const std::vector<BowVector> seq = route(order, rng);
  const int revisit_first = 54 * kKeyframesPerPlace,
            revisit_end = revisit_first + kKeyframesPerPlace;
  const int place3_first = 3 * kKeyframesPerPlace,
            place3_last = place3_first + kKeyframesPerPlace - 1;

  PlaceDatabaseParams params;
  PlaceDatabase db(params, seq.size(), static_cast<std::size_t>(world().voc.numWords()));
  std::vector<PlaceCandidate> out;
  int first_report = -1;
  for (int i = 0; i < static_cast<int>(seq.size()); ++i) {
    ASSERT_TRUE(db.query(seq[static_cast<std::size_t>(i)], i, out).isOk());
    const PlaceQueryStats& st = db.lastQueryStats();
    if (i >= revisit_first && i < revisit_end) {
      std::printf(
          "revisit query %d: prior %.3f touched %d matches %d islands %d best [%d, %d] "
          "streak %d -> %zu candidates\n",
          i, st.prior_score, st.last_query_touched, st.matches, st.islands, st.best_island_first,
          st.best_island_last, st.streak, out.size());
      if (!out.empty() && first_report < 0) first_report = i;
      if (i >= revisit_first + params.temporal_consistency) {
        ASSERT_FALSE(out.empty()) << i;
      }
      for (const PlaceCandidate& c : out) {
        EXPECT_GE(c.keyframe_id, place3_first);
        EXPECT_LE(c.keyframe_id, place3_last);
        EXPECT_GE(c.island_first, place3_first);
        EXPECT_LE(c.island_last, place3_last);
        EXPECT_GE(c.normalised_score, params.min_normalised_score);
        EXPECT_GT(c.score, 0.0);
      }
      for (std::size_t j = 1; j < out.size(); ++j) EXPECT_GE(out[j - 1].score, out[j].score);
      EXPECT_LE(out.size(), static_cast<std::size_t>(params.max_results));
    } else {
      EXPECT_TRUE(out.empty()) << "query " << i << " of a place never seen before";
    }
    ASSERT_TRUE(db.add(i, seq[static_cast<std::size_t>(i)]).isOk());
  }
  // Temporal consistency: not on the first revisit keyframes.
  EXPECT_GE(first_report, revisit_first + params.temporal_consistency - 1);
  EXPECT_GT(db.memoryBytes(), 0u);
  std::printf("memory %zu bytes for %zu keyframes\n", db.memoryBytes(), db.size());
}

TEST(PlaceDatabase, RecentKeyframesAreNeverCandidates) {
  std::mt19937_64 rng(8);
  // One place for 6 * 5 = 30 keyframes: everything looks like a loop, but all of it is recent.
  const std::vector<BowVector> seq = route({7, 7, 7, 7, 7, 7}, rng);
  PlaceDatabaseParams params;
  params.exclude_recent = 30;
  params.temporal_consistency = 1;
  PlaceDatabase db(params);
  std::vector<PlaceCandidate> out;
  for (int i = 0; i < static_cast<int>(seq.size()); ++i) {
    ASSERT_TRUE(db.query(seq[static_cast<std::size_t>(i)], i, out).isOk());
    EXPECT_TRUE(out.empty());
    EXPECT_EQ(db.lastQueryStats().last_query_touched, 0);
    ASSERT_TRUE(db.add(i, seq[static_cast<std::size_t>(i)]).isOk());
  }
  // With exclude_recent = 20 the same query does see keyframes 0 .. 9, and only those.
  params.exclude_recent = 20;
  PlaceDatabase db20(params);
  for (int i = 0; i < static_cast<int>(seq.size()); ++i)
    ASSERT_TRUE(db20.add(i, seq[static_cast<std::size_t>(i)]).isOk());
  const int q = static_cast<int>(seq.size());
  ASSERT_TRUE(db20.query(seq.back(), q, out).isOk());
  ASSERT_FALSE(out.empty());
  for (const PlaceCandidate& c : out) EXPECT_LT(c.keyframe_id, q - 20);
  EXPECT_LE(db20.lastQueryStats().last_query_touched, q - 20);
}

TEST(PlaceDatabase, QueryTouchesOnlyKeyframesSharingWords) {
  std::mt19937_64 rng(9);
  std::vector<int> order;
  for (int p = 0; p < 40; ++p) order.push_back(p);
  const std::vector<BowVector> seq = route(order, rng);
  PlaceDatabaseParams params;
  PlaceDatabase db(params);
  std::vector<PlaceCandidate> out;
  long touched_total = 0, eligible_total = 0;
  for (int i = 0; i < static_cast<int>(seq.size()); ++i) {
    const BowVector& v = seq[static_cast<std::size_t>(i)];
    ASSERT_TRUE(db.query(v, i, out).isOk());
    if (!db.lastQueryStats().skipped) {
      int sharing = 0;  // brute force: eligible keyframes with a common word
      for (int k = 0; k < i - params.exclude_recent; ++k)
        sharing += BinaryVocabulary::score(v, seq[static_cast<std::size_t>(k)]) > 0;
      EXPECT_EQ(db.lastQueryStats().last_query_touched, sharing) << i;
      touched_total += sharing;
      eligible_total += std::max(0, i - params.exclude_recent);
    }
    ASSERT_TRUE(db.add(i, v).isOk());
  }
  std::printf("touched %ld of %ld eligible keyframes\n", touched_total, eligible_total);
  EXPECT_LT(touched_total, eligible_total / 2);
}

TEST(PlaceDatabase, DeterministicAcrossRuns) {
  auto run = [] {
    std::mt19937_64 rng(10);
    std::vector<int> order;
    for (int p = 0; p < 30; ++p) order.push_back(p);
    for (int p = 2; p < 6; ++p) order.push_back(p);
    const std::vector<BowVector> seq = route(order, rng);
    PlaceDatabase db{PlaceDatabaseParams{}};
    std::vector<PlaceCandidate> out;
    std::vector<std::pair<int, double>> log;
    for (int i = 0; i < static_cast<int>(seq.size()); ++i) {
      EXPECT_TRUE(db.query(seq[static_cast<std::size_t>(i)], i, out).isOk());
      for (const auto& c : out) log.emplace_back(c.keyframe_id, c.score);
      EXPECT_TRUE(db.add(i, seq[static_cast<std::size_t>(i)]).isOk());
    }
    return log;
  };
  const auto a = run();
  EXPECT_FALSE(a.empty());
  EXPECT_EQ(a, run());
}

}  // namespace
}  // namespace svslam
