#pragma once
// Place recognition over keyframes' bag-of-words vectors (DBoW2 / DLoopDetector, Galvez-Lopez &
// Tardos 2012, sec. V).
//
// Storage. Keyframes are added with consecutive ids 0, 1, 2, ...; each keeps its BoW vector and
// appears in the inverted list of every word it holds as (keyframe id, weight), lists ordered by
// id. A query reads only the inverted lists of its own words, so it touches only keyframes that
// share a word with it; its cost is the number of such list entries, not the database size.
//
// Query q (BoW vector v, id q; the keyframe q itself need not be in the database):
//  1. Prior: s_prior = s(v, v_{q-1}) (BinaryVocabulary::score) against the previous keyframe.
//     When keyframe q - 1 is not in the database or s_prior < min_prior_score the query is
//     skipped: no candidates, and the temporal consistency streak is reset.
//  2. Scores: for every keyframe k < q - exclude_recent sharing a word with v,
//     s_k = sum over common words min(v_w, v_k,w), which equals the DBoW2 L1 score for
//     L1-normalised vectors; normalised score eta_k = s_k / s_prior. Keyframes with
//     eta_k >= min_normalised_score are matches.
//  3. Islands: matches sorted by id are cut into islands wherever two consecutive matches are
//     more than island_span ids apart. Island score = sum of its s_k; its representative is its
//     best keyframe (highest s_k, ties -> lowest id). The best island has the highest score
//     (ties -> lowest first id).
//  4. Temporal consistency: the best island continues the streak when it overlaps the previous
//     query's best island with ranges extended by island_span ([first - span, last + span]
//     intersect); otherwise the streak restarts at 1 (0 when there is no island). The island is
//     reported when the streak (current query included) is >= temporal_consistency.
//  5. Output: the reported island's keyframes in decreasing s_k (ties -> lower id), at most
//     max_results, the representative first; each carries the island's first and last id.
//
// Determinism and cost: results depend only on the added vectors and the queries; no allocation
// per query once the scratch has grown with the database (add() grows it).
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/status.hpp"
#include "loop/binary_vocabulary.hpp"

namespace svslam {

struct PlaceDatabaseParams {
  double min_normalised_score = 0.3;  // eta = s / s_prior threshold of a match, >= 0
  double min_prior_score = 0.005;     // queries whose s_prior is below this are skipped, >= 0
  int exclude_recent = 20;            // keyframes q - exclude_recent .. q - 1 are never candidates,
                                      // >= 0
  int island_span = 3;                // max id gap inside an island (and island overlap), >= 1
  int temporal_consistency = 3;       // consecutive consistent queries before reporting, >= 1
  int max_results = 3;                // keyframes reported from the island, >= 1
  Status validate() const;
};

struct PlaceCandidate {
  int keyframe_id = -1;
  double score = 0;                         // s_k, DBoW2 L1 score in [0, 1]
  double normalised_score = 0;              // s_k / s_prior
  int island_first = -1, island_last = -1;  // id range of the island the keyframe belongs to
};

struct PlaceQueryStats {
  bool skipped = false;          // no previous keyframe or s_prior < min_prior_score
  double prior_score = 0;        // s_prior
  int last_query_touched = 0;    // distinct keyframes read through the inverted lists
  std::size_t entries_read = 0;  // inverted-list entries read
  int matches = 0;               // keyframes with eta >= min_normalised_score
  int islands = 0;
  int best_island_first = -1, best_island_last = -1;
  double best_island_score = 0;
  int streak = 0;  // consecutive queries whose best islands overlap, this one included
};

class PlaceDatabase {
 public:
  // expected_keyframes reserves storage up front. num_words (the vocabulary's numWords()) bounds
  // the word ids add() accepts; 0 = unknown, then ids up to kMaxWordsUnknown - 1 are accepted.
  static constexpr std::size_t kMaxWordsUnknown = std::size_t{1} << 24;
  explicit PlaceDatabase(const PlaceDatabaseParams& params, std::size_t expected_keyframes = 0,
                         std::size_t num_words = 0);
  const Status& initStatus() const { return init_status_; }

  // Adds keyframe `keyframe_id`, which must equal size(), with a vector of increasing word ids
  // (below the word bound) and finite weights > 0; invalidArgument otherwise.
  Status add(int keyframe_id, const BowVector& v);

  // Candidates for query `query_id` (>= 0) with vector v, see the header comment. `out` is
  // cleared first. Advances the temporal-consistency state (queries are a sequence).
  Status query(const BowVector& v, int query_id, std::vector<PlaceCandidate>& out);

  const PlaceQueryStats& lastQueryStats() const { return stats_; }
  std::size_t size() const { return vectors_.size(); }
  // Approximate heap use (capacities of every container), bytes.
  std::size_t memoryBytes() const;

 private:
  struct Entry {
    std::int32_t keyframe_id;
    float weight;
  };
  struct Match {
    std::int32_t keyframe_id;
    double score;
  };

  PlaceDatabaseParams params_;
  Status init_status_;
  std::vector<BowVector> vectors_;            // per keyframe
  std::vector<std::vector<Entry>> inverted_;  // per word
  std::size_t max_words_ = kMaxWordsUnknown;  // word ids must be below this
  std::vector<double> accumulated_;           // per keyframe, 0 outside a query
  std::vector<std::int32_t> touched_;         // keyframes touched by the current query
  std::vector<Match> matches_;                // scratch: matches of the current query
  bool have_previous_island_ = false;
  int previous_first_ = -1, previous_last_ = -1;
  int streak_ = 0;
  PlaceQueryStats stats_;
};

}  // namespace svslam
