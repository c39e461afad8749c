// BinaryVocabulary: majority centres, deterministic training, word repeatability under noise,
// idf, the L1 score, serialisation and its failure modes.
#include "loop/binary_vocabulary.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>
#include <random>
#include <set>
#include <vector>

#include "loop_test_support.hpp"

namespace svslam {
namespace {

using namespace loop_test;  // NOLINT: the shared fixtures

OrbDescriptor withBits(std::initializer_list<int> bits) {
  OrbDescriptor d;
  for (int j : bits) d.words[static_cast<std::size_t>(j / 64)] |= std::uint64_t{1} << (j % 64);
  return d;
}

// Images of noisy copies (10 % flips) of the same prototypes.
std::vector<std::vector<OrbDescriptor>> noisyImages(const std::vector<OrbDescriptor>& protos,
                                                    int num_images, std::mt19937_64& rng) {
  std::vector<std::vector<OrbDescriptor>> images;
  for (int i = 0; i < num_images; ++i) images.push_back(keyframeOf(protos, 0.7, 0.1, rng));
  return images;
}

TEST(BinaryVocabulary, MajorityCentreHandCase) {
  const std::vector<OrbDescriptor> three = {withBits({0, 1, 70, 255}), withBits({0, 70, 200}),
                                            withBits({70, 130, 255})};
  EXPECT_EQ(bitwiseMajority(three), withBits({0, 70, 255}));
  // Two members: a bit set in one of them is a tie and goes to 0.
  const std::vector<OrbDescriptor> two = {withBits({3, 64, 65}), withBits({3, 66})};
  EXPECT_EQ(bitwiseMajority(two), withBits({3}));
  EXPECT_EQ(bitwiseMajority({}), OrbDescriptor{});
}

TEST(BinaryVocabulary, BadArguments) {
  VocabularyParams p;
  EXPECT_EQ(BinaryVocabulary::train({}, p).status().code(), StatusCode::kInvalidArgument);
  std::mt19937_64 rng(1);
  EXPECT_EQ(BinaryVocabulary::train({randomDescriptors(5, rng)}, p).status().code(),
            StatusCode::kInvalidArgument);
  p.branching = 1;
  EXPECT_FALSE(p.validate().isOk());
  p = VocabularyParams{};
  p.depth = 0;
  EXPECT_EQ(BinaryVocabulary::train({randomDescriptors(50, rng)}, p).status().code(),
            StatusCode::kInvalidArgument);
  p = VocabularyParams{};
  p.max_iterations = 0;
  EXPECT_FALSE(p.validate().isOk());
}

TEST(BinaryVocabulary, TrainingIsDeterministicForASeed) {
  std::mt19937_64 rng(3);
  const auto images = noisyImages(randomDescriptors(300, rng), 8, rng);
  VocabularyParams p;
  p.branching = 6;
  p.depth = 3;
  auto a = BinaryVocabulary::train(images, p), b = BinaryVocabulary::train(images, p);
  ASSERT_TRUE(a.isOk() && b.isOk());
  EXPECT_EQ(a->serialize(), b->serialize());
  p.seed = 8;
  auto c = BinaryVocabulary::train(images, p);
  ASSERT_TRUE(c.isOk());
  EXPECT_NE(a->serialize(), c->serialize());
}

TEST(BinaryVocabulary, NoisyCopiesOfAPrototypeShareAWord) {
  std::mt19937_64 rng(11);
  const auto protos = randomDescriptors(60, rng);
  VocabularyParams p;
  p.branching = 8;
  p.depth = 3;
  auto voc = BinaryVocabulary::train(noisyImages(protos, 20, rng), p);
  ASSERT_TRUE(voc.isOk());
  // Fresh copies, never seen in training: pairs of copies of one prototype.
  int same = 0, trials = 0;
  for (const auto& proto : protos)
    for (int t = 0; t < 20; ++t, ++trials)
      same += voc->wordOf(noisyCopy(proto, 0.1, rng)) == voc->wordOf(noisyCopy(proto, 0.1, rng));
  const double rate = static_cast<double>(same) / trials, chance = 1.0 / voc->numWords();
  std::printf("words %d, same word %.3f (chance %.4f)\n", voc->numWords(), rate, chance);
  EXPECT_GT(rate, 0.7);
  EXPECT_GT(rate, 50 * chance);
}

TEST(BinaryVocabulary, IdfOfAWordInEveryImageIsZero) {
  std::mt19937_64 rng(5);
  const OrbDescriptor common = randomDescriptor(rng);
  std::vector<std::vector<OrbDescriptor>> images;
  for (int i = 0; i < 12; ++i) {
    images.push_back(randomDescriptors(40, rng));
    images.back().push_back(common);
  }
  VocabularyParams p;
  p.branching = 5;
  p.depth = 3;
  auto voc = BinaryVocabulary::train(images, p);
  ASSERT_TRUE(voc.isOk());
  EXPECT_EQ(voc->idf(voc->wordOf(common)), 0.0f);
  BowVector v;
  voc->transform({common, common}, v);
  EXPECT_TRUE(v.empty());  // a stop word only: nothing left
  for (int w = 0; w < voc->numWords(); ++w) {
    EXPECT_GE(voc->idf(static_cast<std::uint32_t>(w)), 0.0f);
    EXPECT_LE(voc->idf(static_cast<std::uint32_t>(w)), std::log(12.0f) + 1e-6f);
  }
}

TEST(BinaryVocabulary, TransformIsSortedAndL1Normalised) {
  std::mt19937_64 rng(6);
  const auto protos = randomDescriptors(200, rng);
  auto voc = BinaryVocabulary::train(noisyImages(protos, 10, rng), VocabularyParams{});
  ASSERT_TRUE(voc.isOk());
  BowVector v;
  std::vector<std::uint32_t> ids;
  const auto desc = keyframeOf(protos, 0.5, 0.1, rng);
  voc->transform(desc, v, ids);
  ASSERT_EQ(ids.size(), desc.size());
  for (std::size_t i = 0; i < desc.size(); ++i) EXPECT_EQ(ids[i], voc->wordOf(desc[i]));
  ASSERT_FALSE(v.empty());
  double sum = 0;
  for (std::size_t i = 0; i < v.size(); ++i) {
    EXPECT_GT(v[i].second, 0.0f);
    if (i > 0) {
      EXPECT_LT(v[i - 1].first, v[i].first);
    }
    sum += v[i].second;
  }
  EXPECT_NEAR(sum, 1.0, 1e-5);
  voc->transform({}, v);
  EXPECT_TRUE(v.empty());
}

TEST(BinaryVocabulary, ScoreProperties) {
  const BowVector a = {{1, 0.5f}, {4, 0.25f}, {9, 0.25f}};
  const BowVector b = {{2, 0.5f}, {5, 0.5f}};
  const BowVector c = {{1, 0.25f}, {5, 0.25f}, {9, 0.5f}};
  EXPECT_DOUBLE_EQ(BinaryVocabulary::score(a, a), 1.0);
  EXPECT_DOUBLE_EQ(BinaryVocabulary::score(a, b), 0.0);
  EXPECT_DOUBLE_EQ(BinaryVocabulary::score(a, c), BinaryVocabulary::score(c, a));
  // 1 - 0.5 (|0.5-0.25| + 0.25 + 0.25 + |0.25-0.5|) = 0.5
  EXPECT_DOUBLE_EQ(BinaryVocabulary::score(a, c), 0.5);
  EXPECT_DOUBLE_EQ(BinaryVocabulary::score(a, {}), 0.0);

  std::mt19937_64 rng(8);
  const auto protos = randomDescriptors(300, rng);
  auto voc = BinaryVocabulary::train(noisyImages(protos, 10, rng), VocabularyParams{});
  ASSERT_TRUE(voc.isOk());
  BowVector x, y;
  for (int t = 0; t < 20; ++t) {
    voc->transform(keyframeOf(protos, 0.6, 0.1, rng), x);
    voc->transform(keyframeOf(protos, 0.6, 0.1, rng), y);
    const double s = BinaryVocabulary::score(x, y);
    EXPECT_GE(s, 0.0);
    EXPECT_LE(s, 1.0);
    EXPECT_DOUBLE_EQ(s, BinaryVocabulary::score(y, x));
    EXPECT_NEAR(BinaryVocabulary::score(x, x), 1.0, 1e-6);
  }
}

TEST(BinaryVocabulary, SerializeRoundTrip) {
  std::mt19937_64 rng(9);
  std::vector<std::vector<OrbDescriptor>> images;
  for (int i = 0; i < 40; ++i) images.push_back(randomDescriptors(500, rng));
  auto voc = BinaryVocabulary::train(images, VocabularyParams{});  // k = 10, L = 4
  ASSERT_TRUE(voc.isOk());
  const std::vector<std::uint8_t> bytes = voc->serialize();
  EXPECT_EQ(bytes.size(), 22u + 33u * static_cast<std::size_t>(voc->numNodes()) +
                              4u * static_cast<std::size_t>(voc->numWords()));
  EXPECT_LT(bytes.size(), 5u << 20);
  std::printf("k=10 L=4: %d nodes, %d words, %zu bytes\n", voc->numNodes(), voc->numWords(),
              bytes.size());
  auto back = BinaryVocabulary::deserialize(bytes.data(), bytes.size());
  ASSERT_TRUE(back.isOk()) << back.status().message();
  EXPECT_EQ(back->numWords(), voc->numWords());
  EXPECT_EQ(back->serialize(), bytes);
  BowVector a, b;
  for (int t = 0; t < 5; ++t) {
    const auto desc = randomDescriptors(300, rng);
    voc->transform(desc, a);
    back->transform(desc, b);
    EXPECT_EQ(a, b);
  }
}

TEST(BinaryVocabulary, CorruptBytesAreRejectedWithoutCrashing) {
  std::mt19937_64 rng(10);
  VocabularyParams p;
  p.branching = 4;
  p.depth = 2;
  auto voc = BinaryVocabulary::train(noisyImages(randomDescriptors(40, rng), 6, rng), p);
  ASSERT_TRUE(voc.isOk());
  const std::vector<std::uint8_t> good = voc->serialize();
  auto code = [](const std::vector<std::uint8_t>& b) {
    return BinaryVocabulary::deserialize(b.data(), b.size()).status().code();
  };
  ASSERT_EQ(code(good), StatusCode::kOk);
  for (std::size_t n = 0; n < good.size(); ++n) {  // every truncation
    auto r = BinaryVocabulary::deserialize(good.data(), n);
    ASSERT_EQ(r.status().code(), StatusCode::kCorruptData) << n;
    EXPECT_NE(r.status().message().find("vocabulary"), std::string::npos);
  }
  EXPECT_EQ(BinaryVocabulary::deserialize(nullptr, 0).status().code(), StatusCode::kCorruptData);
  auto bad = good;
  bad[0] = 'X';
  EXPECT_EQ(code(bad), StatusCode::kCorruptData);
  bad = good;
  bad.push_back(0);  // trailing byte
  EXPECT_EQ(code(bad), StatusCode::kCorruptData);
  bad = good;
  bad[18] = 0xFF;  // node count far beyond the size
  EXPECT_EQ(code(bad), StatusCode::kCorruptData);
  bad = good;
  bad[6] = 2;  // version
  EXPECT_EQ(code(bad), StatusCode::kCorruptData);
  bad = good;  // NaN idf in the last leaf (the file ends with it)
  const float nan = std::nanf("");
  std::memcpy(bad.data() + bad.size() - 4, &nan, 4);
  auto r = BinaryVocabulary::deserialize(bad.data(), bad.size());
  EXPECT_EQ(r.status().code(), StatusCode::kCorruptData);
  EXPECT_NE(r.status().message().find("idf"), std::string::npos) << r.status().message();
  bad = good;
  bad[22] = static_cast<std::uint8_t>(bad[22] + 1);  // root child count: the tree no longer adds up
  EXPECT_EQ(code(bad), StatusCode::kCorruptData);
  // Random corruption: any outcome but a crash; a success must be usable.
  for (int t = 0; t < 2000; ++t) {
    bad = good;
    const int flips = 1 + static_cast<int>(rng() % 4);
    for (int f = 0; f < flips; ++f)
      bad[rng() % bad.size()] ^= static_cast<std::uint8_t>(1 + rng() % 255);
    auto v = BinaryVocabulary::deserialize(bad.data(), bad.size());
    if (v.isOk()) {
      BowVector out;
      v->transform(randomDescriptors(20, rng), out);
    } else {
      EXPECT_EQ(v.status().code(), StatusCode::kCorruptData);
    }
  }
}

}  // namespace
}  // namespace svslam
