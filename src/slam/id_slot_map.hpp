#pragma once
// IdSlotMap: landmark id -> slot, for ids that are handed out for ever (0, 1, 2, ...) but of
// which only a bounded number are live at once. A table indexed by id grows with every id ever
// created (4 bytes each: 3.6 MB after an hour at 250 new landmarks per second, and iterating it
// grows as long); this one grows only with the largest number of ids live at once.
//
// Open addressing with linear probing and backward-shift deletion (no tombstones, so probe
// lengths depend on the live count alone). Capacity is a power of two kept >= 2x the live count
// (load <= 0.5); it doubles, rehashing, when an insert would pass that, and never shrinks.
// Iteration order is the table's, not the ids'.
#include <cstddef>
#include <cstdint>
#include <vector>

namespace svslam {

class IdSlotMap {
 public:
  explicit IdSlotMap(int expected_live = 0) { reserve(expected_live); }

  // Room for `n` live ids without a rehash.
  void reserve(int n);
  // Slot of `id`, or -1 when absent (any id, negative included).
  int find(int id) const {
    if (id < 0) return -1;
    for (std::size_t i = home(id);; i = (i + 1) & mask_) {
      const Entry& e = table_[i];
      if (e.id == id) return e.slot;
      if (e.id < 0) return -1;
    }
  }
  bool contains(int id) const { return find(id) >= 0; }
  // Sets the slot of `id` (>= 0), inserting it when absent. Precondition: id >= 0, slot >= 0.
  void set(int id, int slot);
  // Removes `id`; false when it was absent.
  bool erase(int id);
  void clear();
  int size() const { return size_; }
  std::size_t capacity() const { return table_.size(); }

  // f(id, slot) for each live id, in table order.
  template <class F>
  void forEach(F&& f) const {
    for (const Entry& e : table_)
      if (e.id >= 0) f(e.id, e.slot);
  }

 private:
  struct Entry {
    int id = -1;  // -1: empty
    int slot = -1;
  };
  // Fibonacci hashing of the id onto the table (ids are consecutive; this spreads them).
  std::size_t home(int id) const {
    return static_cast<std::size_t>((static_cast<std::uint64_t>(static_cast<std::uint32_t>(id)) *
                                     0x9E3779B97F4A7C15ull) >>
                                    shift_) &
           mask_;
  }
  void rehash(std::size_t capacity);

  std::vector<Entry> table_;
  std::size_t mask_ = 0;
  int shift_ = 64;
  int size_ = 0;
};

}  // namespace svslam
