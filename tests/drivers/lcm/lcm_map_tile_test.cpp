// map_tile_t: a tile round-trips through the wire bytes (rows flipped to south-up on the wire
// and back), and malformed tiles and messages are rejected with a clear error.
#include "drivers/lcm/lcm_map_tile.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "svslam_lcm/map_tile_t.hpp"

namespace svslam::drivers {
namespace {

// An n x n tile (tile_i, tile_j) with distinct values per cell and a few empty cells.
map::DemRaster sampleTile(int n, int tile_i, int tile_j) {
  map::DemRaster t;
  t.cell_m = 0.25;
  t.i0 = tile_i * n;
  t.j0 = tile_j * n;
  t.resize(n, n);
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) {
      const std::size_t k = t.index(c, r);
      if ((r * 7 + c) % 5 == 0) continue;  // no data
      t.height_m[k] = 0.01f * static_cast<float>(r * n + c) - 3.0f;
      t.sigma_m[k] = 0.001f * static_cast<float>(c + 1);
      t.count[k] = static_cast<float>(r + c + 1);
      t.luminance[k] = static_cast<std::uint8_t>((r * 31 + c) & 0xFF);
    }
  return t;
}

bool sameOrBothNan(float a, float b) { return (std::isnan(a) && std::isnan(b)) || a == b; }

std::vector<std::uint8_t> encodeRaw(const svslam_lcm::map_tile_t& m) {
  std::vector<std::uint8_t> b(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

svslam_lcm::map_tile_t rawTile(int n, int num_cells) {
  svslam_lcm::map_tile_t m;
  m.t_ns = 1;
  m.seq = 2;
  m.tile_i = 0;
  m.tile_j = 0;
  m.cells_per_side = n;
  m.cell_m = 0.1;
  m.num_cells = num_cells;
  m.height_m.assign(static_cast<std::size_t>(num_cells), 0.0f);
  m.sigma_m.assign(static_cast<std::size_t>(num_cells), 0.0f);
  m.count.assign(static_cast<std::size_t>(num_cells), 0);
  m.luminance.assign(static_cast<std::size_t>(num_cells), 0);
  return m;
}

}  // namespace

TEST(LcmMapTile, RoundTripKeepsTheRaster) {
  const int n = 16;
  const map::DemRaster t = sampleTile(n, -3, 5);
  std::vector<std::uint8_t> bytes;
  ASSERT_TRUE(encodeMapTile(t, -3, 5, 123'456'789'000, 42, bytes));
  MapTileMessage back;
  const Status s = decodeMapTile(bytes.data(), bytes.size(), back);
  ASSERT_TRUE(s) << s.message();
  EXPECT_EQ(back.t_ns, 123'456'789'000);
  EXPECT_EQ(back.seq, 42);
  EXPECT_EQ(back.tile_i, -3);
  EXPECT_EQ(back.tile_j, 5);
  EXPECT_EQ(back.tile.cell_m, t.cell_m);
  EXPECT_EQ(back.tile.i0, t.i0);
  EXPECT_EQ(back.tile.j0, t.j0);
  ASSERT_EQ(back.tile.cols, n);
  ASSERT_EQ(back.tile.rows, n);
  for (std::size_t k = 0; k < t.height_m.size(); ++k) {
    EXPECT_TRUE(sameOrBothNan(back.tile.height_m[k], t.height_m[k])) << k;
    EXPECT_TRUE(sameOrBothNan(back.tile.sigma_m[k], t.sigma_m[k])) << k;
    EXPECT_EQ(back.tile.count[k], t.count[k]) << k;
    EXPECT_EQ(back.tile.luminance[k], t.luminance[k]) << k;
  }
}

TEST(LcmMapTile, WireRowZeroIsSmallestY) {
  const int n = 8;
  map::DemRaster t = sampleTile(n, 1, 2);
  int col = 0, row = 0;
  ASSERT_TRUE(t.cellToPixel(t.i0 + 3, t.j0, col, row));  // smallest y: the raster's last row
  EXPECT_EQ(row, n - 1);
  t.height_m[t.index(col, row)] = 77.0f;
  std::vector<std::uint8_t> bytes;
  ASSERT_TRUE(encodeMapTile(t, 1, 2, 0, 0, bytes));
  svslam_lcm::map_tile_t m;
  ASSERT_EQ(m.decode(bytes.data(), 0, static_cast<int>(bytes.size())),
            static_cast<int>(bytes.size()));
  EXPECT_EQ(m.height_m[3], 77.0f);  // wire [r = 0, c = 3]
}

TEST(LcmMapTile, CountsSaturate) {
  map::DemRaster t = sampleTile(8, 0, 0);
  t.count[0] = 1e6f;
  t.count[1] = -5.0f;
  t.count[2] = NAN;
  t.count[3] = 2.6f;
  std::vector<std::uint8_t> bytes;
  ASSERT_TRUE(encodeMapTile(t, 0, 0, 0, 0, bytes));
  MapTileMessage back;
  ASSERT_TRUE(decodeMapTile(bytes.data(), bytes.size(), back));
  EXPECT_EQ(back.tile.count[0], 32767.0f);
  EXPECT_EQ(back.tile.count[1], 0.0f);
  EXPECT_EQ(back.tile.count[2], 0.0f);
  EXPECT_EQ(back.tile.count[3], 3.0f);
}

TEST(LcmMapTile, BadTilesAreNotEncoded) {
  std::vector<std::uint8_t> bytes;
  map::DemRaster t = sampleTile(8, 0, 0);
  map::DemRaster wide = t;
  wide.resize(8, 4);
  EXPECT_FALSE(encodeMapTile(wide, 0, 0, 0, 0, bytes));
  map::DemRaster empty;
  EXPECT_FALSE(encodeMapTile(empty, 0, 0, 0, 0, bytes));
  map::DemRaster big;
  big.resize(kMaxMapTileCells + 1, kMaxMapTileCells + 1);
  EXPECT_FALSE(encodeMapTile(big, 0, 0, 0, 0, bytes));
  map::DemRaster short_array = t;
  short_array.sigma_m.pop_back();
  EXPECT_FALSE(encodeMapTile(short_array, 0, 0, 0, 0, bytes));
  map::DemRaster nan_cell = t;
  nan_cell.cell_m = NAN;
  const Status s = encodeMapTile(nan_cell, 0, 0, 0, 0, bytes);
  EXPECT_FALSE(s);
  EXPECT_NE(s.message().find("cell_m"), std::string::npos) << s.message();
  EXPECT_FALSE(encodeMapTile(t, 1, 0, 0, 0, bytes));  // i0 is not tile 1's
}

TEST(LcmMapTile, MalformedMessagesAreRejected) {
  MapTileMessage out;
  auto expectCorrupt = [&out](const std::vector<std::uint8_t>& b, const std::string& what) {
    const Status s = decodeMapTile(b.data(), b.size(), out);
    EXPECT_EQ(s.code(), StatusCode::kCorruptData) << what;
    EXPECT_NE(s.message().find("map_tile_t"), std::string::npos) << s.message();
    return s.message();
  };
  std::vector<std::uint8_t> good;
  ASSERT_TRUE(encodeMapTile(sampleTile(8, 0, 0), 0, 0, 0, 0, good));

  std::vector<std::uint8_t> truncated(good.begin(), good.end() - 1);
  expectCorrupt(truncated, "truncated");
  std::vector<std::uint8_t> longer = good;
  longer.push_back(0);
  expectCorrupt(longer, "trailing byte");
  std::vector<std::uint8_t> garbage = good;
  garbage[0] ^= 0xFF;
  EXPECT_NE(expectCorrupt(garbage, "hash").find("hash"), std::string::npos);
  expectCorrupt({}, "empty");

  EXPECT_NE(expectCorrupt(encodeRaw(rawTile(4, 15)), "n*n mismatch").find("num_cells"),
            std::string::npos);
  EXPECT_NE(expectCorrupt(encodeRaw(rawTile(0, 0)), "n = 0").find("cells_per_side"),
            std::string::npos);
  EXPECT_NE(expectCorrupt(encodeRaw(rawTile(-2, 4)), "n < 0").find("cells_per_side"),
            std::string::npos);
  EXPECT_NE(expectCorrupt(encodeRaw(rawTile(1025, 1)), "n > 1024").find("cells_per_side"),
            std::string::npos);
  svslam_lcm::map_tile_t m = rawTile(4, 16);
  m.cell_m = std::numeric_limits<double>::infinity();
  EXPECT_NE(expectCorrupt(encodeRaw(m), "cell_m").find("cell_m"), std::string::npos);
  m = rawTile(4, 16);
  m.count[3] = -1;
  expectCorrupt(encodeRaw(m), "negative count");
  // num_cells claims more cells than the bytes hold (lcm-gen would allocate them).
  std::vector<std::uint8_t> lying = encodeRaw(rawTile(4, 16));
  lying[44] = 0x7F;
  expectCorrupt(lying, "lying num_cells");

  EXPECT_TRUE(decodeMapTile(good.data(), good.size(), out));
}

}  // namespace svslam::drivers
