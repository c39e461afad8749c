#include "loop/place_database.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace svslam {

Status PlaceDatabaseParams::validate() const {
  if (!(min_normalised_score >= 0))
    return Status::invalidArgument("min_normalised_score must be >= 0");
  if (!(min_prior_score >= 0)) return Status::invalidArgument("min_prior_score must be >= 0");
  if (exclude_recent < 0) return Status::invalidArgument("exclude_recent must be >= 0");
  if (island_span < 1) return Status::invalidArgument("island_span must be >= 1");
  if (temporal_consistency < 1) return Status::invalidArgument("temporal_consistency must be >= 1");
  if (max_results < 1) return Status::invalidArgument("max_results must be >= 1");
  return Status::ok();
}

PlaceDatabase::PlaceDatabase(const PlaceDatabaseParams& params, std::size_t expected_keyframes,
                             std::size_t num_words)
    : params_(params), init_status_(params.validate()) {
  vectors_.reserve(expected_keyframes);
  accumulated_.reserve(expected_keyframes);
  touched_.reserve(expected_keyframes);
  matches_.reserve(expected_keyframes);
  inverted_.resize(num_words);
  if (num_words > 0) max_words_ = num_words;
}

Status PlaceDatabase::add(int keyframe_id, const BowVector& v) {
  if (!init_status_) return init_status_;
  if (keyframe_id < 0 || static_cast<std::size_t>(keyframe_id) != vectors_.size())
    return Status::invalidArgument("place database: keyframe id " + std::to_string(keyframe_id) +
                                   " added, expected " + std::to_string(vectors_.size()));
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (!(v[i].second > 0) || !std::isfinite(v[i].second) ||
        (i > 0 && v[i - 1].first >= v[i].first))
      return Status::invalidArgument(
          "place database: BoW vector needs increasing word ids and finite weights > 0");
  }
  if (!v.empty() && v.back().first >= max_words_)
    return Status::invalidArgument("place database: word id " + std::to_string(v.back().first) +
                                   " beyond the vocabulary (" + std::to_string(max_words_) +
                                   " words)");
  if (!v.empty() && v.back().first >= inverted_.size()) inverted_.resize(v.back().first + 1u);
  for (const auto& [w, weight] : v) inverted_[w].push_back({keyframe_id, weight});
  vectors_.push_back(v);
  accumulated_.push_back(0.0);
  touched_.reserve(vectors_.size());
  matches_.reserve(vectors_.size());
  return Status::ok();
}

Status PlaceDatabase::query(const BowVector& v, int query_id, std::vector<PlaceCandidate>& out) {
  if (!init_status_) return init_status_;
  if (query_id < 0) return Status::invalidArgument("place database: query id must be >= 0");
  out.clear();
  stats_ = PlaceQueryStats{};
  const auto n = static_cast<std::int64_t>(vectors_.size());
  const std::int64_t previous = query_id - 1;
  if (previous >= 0 && previous < n)
    stats_.prior_score = BinaryVocabulary::score(v, vectors_[static_cast<std::size_t>(previous)]);
  if (previous < 0 || previous >= n || stats_.prior_score < params_.min_prior_score ||
      stats_.prior_score <= 0) {
    stats_.skipped = true;
    streak_ = 0;
    have_previous_island_ = false;
    return Status::ok();
  }

  // 1. Accumulate min(v_w, v_k,w) over the inverted lists, eligible keyframes only.
  const std::int64_t limit =
      std::min<std::int64_t>(n, std::int64_t{query_id} - params_.exclude_recent);
  touched_.clear();
  for (const auto& [w, qw] : v) {
    if (w >= inverted_.size() || !(qw > 0)) continue;
    for (const Entry& e : inverted_[w]) {
      if (e.keyframe_id >= limit) break;  // lists are ordered by id
      ++stats_.entries_read;
      double& acc = accumulated_[static_cast<std::size_t>(e.keyframe_id)];
      if (acc == 0) touched_.push_back(e.keyframe_id);
      acc += std::min(static_cast<double>(qw), static_cast<double>(e.weight));
    }
  }
  stats_.last_query_touched = static_cast<int>(touched_.size());

  // 2. Matches by normalised score, then sorted by id.
  matches_.clear();
  for (std::int32_t k : touched_) {
    double& acc = accumulated_[static_cast<std::size_t>(k)];
    if (acc / stats_.prior_score >= params_.min_normalised_score) matches_.push_back({k, acc});
    acc = 0;
  }
  std::sort(matches_.begin(), matches_.end(),
            [](const Match& a, const Match& b) { return a.keyframe_id < b.keyframe_id; });
  stats_.matches = static_cast<int>(matches_.size());

  // 3. Islands; keep the best one (highest sum, ties -> lowest first id).
  std::size_t best_begin = 0, best_end = 0;
  double best_sum = -1;
  for (std::size_t b = 0; b < matches_.size();) {
    std::size_t e = b + 1;
    double sum = matches_[b].score;
    while (e < matches_.size() &&
           matches_[e].keyframe_id - matches_[e - 1].keyframe_id <= params_.island_span)
      sum += matches_[e++].score;
    ++stats_.islands;
    if (sum > best_sum) best_sum = sum, best_begin = b, best_end = e;
    b = e;
  }
  if (stats_.islands == 0) {
    streak_ = 0;
    have_previous_island_ = false;
    return Status::ok();
  }
  const int first = matches_[best_begin].keyframe_id, last = matches_[best_end - 1].keyframe_id;
  stats_.best_island_first = first;
  stats_.best_island_last = last;
  stats_.best_island_score = best_sum;

  // 4. Temporal consistency against the previous query's best island.
  const bool overlaps = have_previous_island_ && first - params_.island_span <= previous_last_ &&
                        previous_first_ - params_.island_span <= last;
  streak_ = overlaps ? streak_ + 1 : 1;
  have_previous_island_ = true;
  previous_first_ = first;
  previous_last_ = last;
  stats_.streak = streak_;
  if (streak_ < params_.temporal_consistency) return Status::ok();

  // 5. The island's best keyframes, representative first.
  const auto begin = matches_.begin() + static_cast<std::ptrdiff_t>(best_begin);
  const auto end = matches_.begin() + static_cast<std::ptrdiff_t>(best_end);
  const std::ptrdiff_t count = std::min<std::ptrdiff_t>(end - begin, params_.max_results);
  std::partial_sort(begin, begin + count, end, [](const Match& a, const Match& b) {
    return a.score > b.score || (a.score == b.score && a.keyframe_id < b.keyframe_id);
  });
  for (auto it = begin; it != begin + count; ++it)
    out.push_back({it->keyframe_id, it->score, it->score / stats_.prior_score, first, last});
  return Status::ok();
}

std::size_t PlaceDatabase::memoryBytes() const {
  std::size_t bytes =
      vectors_.capacity() * sizeof(BowVector) + inverted_.capacity() * sizeof(std::vector<Entry>) +
      accumulated_.capacity() * sizeof(double) + touched_.capacity() * sizeof(std::int32_t) +
      matches_.capacity() * sizeof(Match);
  for (const BowVector& v : vectors_) bytes += v.capacity() * sizeof(BowVector::value_type);
  for (const auto& list : inverted_) bytes += list.capacity() * sizeof(Entry);
  return bytes;
}

}  // namespace svslam
