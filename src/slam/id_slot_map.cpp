#include "slam/id_slot_map.hpp"

#include <algorithm>

namespace svslam {

void IdSlotMap::reserve(int n) {
  std::size_t cap = 8;
  const std::size_t need = 2 * static_cast<std::size_t>(std::max(n, 0));
  while (cap < need) cap *= 2;
  if (cap > table_.size()) rehash(cap);
}

void IdSlotMap::rehash(std::size_t capacity) {
  std::vector<Entry> old;
  old.swap(table_);
  table_.assign(capacity, Entry{});
  mask_ = capacity - 1;
  int bits = 0;
  while ((std::size_t{1} << bits) < capacity) ++bits;
  shift_ = 64 - bits;
  size_ = 0;
  for (const Entry& e : old)
    if (e.id >= 0) set(e.id, e.slot);
}

void IdSlotMap::set(int id, int slot) {
  for (std::size_t i = home(id);; i = (i + 1) & mask_) {
    Entry& e = table_[i];
    if (e.id == id) {
      e.slot = slot;
      return;
    }
    if (e.id < 0) {
      if (2 * static_cast<std::size_t>(size_ + 1) > table_.size()) {
        rehash(2 * table_.size());
        set(id, slot);
        return;
      }
      e = {id, slot};
      ++size_;
      return;
    }
  }
}

bool IdSlotMap::erase(int id) {
  if (id < 0) return false;
  std::size_t i = home(id);
  while (table_[i].id != id) {
    if (table_[i].id < 0) return false;
    i = (i + 1) & mask_;
  }
  // Backward shift: pull each later entry of the cluster into the hole when its home does not
  // lie cyclically in (hole, j], so every entry stays reachable from its home without a gap.
  std::size_t hole = i;
  for (std::size_t j = (hole + 1) & mask_; table_[j].id >= 0; j = (j + 1) & mask_) {
    const std::size_t h = home(table_[j].id);
    const bool h_in_hole_to_j = hole <= j ? (h > hole && h <= j) : (h > hole || h <= j);
    if (!h_in_hole_to_j) {
      table_[hole] = table_[j];
      hole = j;
    }
  }
  table_[hole] = Entry{};
  --size_;
  return true;
}

void IdSlotMap::clear() {
  std::fill(table_.begin(), table_.end(), Entry{});
  size_ = 0;
}

}  // namespace svslam
