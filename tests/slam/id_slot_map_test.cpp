// IdSlotMap against std::map as the reference: random inserts, overwrites and erases (erase's
// backward shift is where an open-addressing table goes wrong), and a bounded table under the
// id pattern of a long flight: ids handed out for ever, a bounded number live.
#include "slam/id_slot_map.hpp"

#include <gtest/gtest.h>

#include <map>
#include <random>

namespace svslam {
namespace {

void expectSame(const IdSlotMap& m, const std::map<int, int>& ref, int max_id) {
  ASSERT_EQ(m.size(), static_cast<int>(ref.size()));
  for (int id = -2; id <= max_id; ++id) {
    const auto it = ref.find(id);
    ASSERT_EQ(m.find(id), it == ref.end() ? -1 : it->second) << "id " << id;
  }
  std::map<int, int> seen;
  m.forEach([&](int id, int slot) { seen[id] = slot; });
  EXPECT_EQ(seen, ref);
}

TEST(IdSlotMap, MatchesAStdMapUnderRandomSetsAndErases) {
  std::mt19937 rng(7);
  IdSlotMap m;
  std::map<int, int> ref;
  const int kIds = 300;
  for (int step = 0; step < 20000; ++step) {
    const int id = static_cast<int>(rng() % kIds);
    if (rng() % 3 == 0) {
      EXPECT_EQ(m.erase(id), ref.erase(id) == 1);
    } else {
      const int slot = static_cast<int>(rng() % 1000);
      m.set(id, slot);
      ref[id] = slot;
    }
    if (step % 997 == 0) expectSame(m, ref, kIds);
  }
  expectSame(m, ref, kIds);
  EXPECT_LE(2 * static_cast<std::size_t>(m.size()), m.capacity());  // load <= 0.5
  m.clear();
  expectSame(m, {}, kIds);
}

TEST(IdSlotMap, TableIsBoundedByTheLiveIdsNotByTheIdsEverSeen) {
  // A flight's pattern: new ids in order, each live for a while, 150 live at most, a few
  // (anchors) live for ever; a million ids in all.
  IdSlotMap m(200);
  const std::size_t cap0 = m.capacity();
  std::map<int, int> ref;
  for (int id = 0; id < 1000000; ++id) {
    m.set(id, id % 150);
    ref[id] = id % 150;
    const int old = id - 140;
    if (old >= 10) {  // ids 0..9 stay (anchors)
      ASSERT_TRUE(m.erase(old));
      ref.erase(old);
    }
    if (id % 99991 == 0) expectSame(m, ref, id + 1);
  }
  EXPECT_EQ(m.size(), 150);
  EXPECT_EQ(m.capacity(), cap0);  // 512 entries (4 kB), after a million ids
  EXPECT_EQ(m.find(3), 3);
  EXPECT_EQ(m.find(500000), -1);
}

TEST(IdSlotMap, GrowsWhenMoreIdsAreLiveThanReserved) {
  IdSlotMap m(4);
  for (int id = 0; id < 1000; ++id) m.set(id * 7, id);
  EXPECT_EQ(m.size(), 1000);
  EXPECT_GE(m.capacity(), 2000u);
  for (int id = 0; id < 1000; ++id) EXPECT_EQ(m.find(id * 7), id);
  EXPECT_EQ(m.find(1), -1);
  EXPECT_FALSE(m.erase(1));
  EXPECT_FALSE(m.erase(-5));
}

}  // namespace
}  // namespace svslam
