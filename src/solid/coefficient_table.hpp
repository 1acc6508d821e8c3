// SPDX-License-Identifier: MIT
// The contact law's coefficient sets of every contact in the DEM's lists (T1-T7): a table of the
// distinct sets, found by (material a, material b, m*, R*), and per contact an index into it (4
// bytes to stream per pair instead of 40). Equal grains share one set per material pair; a bed of
// many sizes gives nearly every pair its own (add() skips the hash then).
#pragma once
#include <bit>
#include <functional>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "solid/contact_model.hpp"

namespace tessera {

class CoefficientTable {
 public:
  // Starts a new table for law Law of `model` (at each list build or candidate search).
  template <class Law>
  void start(const ContactModel& model) {
    sets_.clear(), index_.clear();
    last_ = {-1, -1, 0, 0}, last_index_ = -1;
    make_ = [&model](int ma, int mb, double meff, double reff) {
      return ContactCoefficients::of<Law>(Law::coefficients(model.pair(ma, mb), meff, reff));
    };
  }
  // The index of the set of (ma, mb, m*, R*), made if new.
  std::int32_t find(int ma, int mb, double meff, double reff) {
    const Key key{ma, mb, meff, reff};
    if (key == last_) return last_index_;  // neighbours in a list are often alike: skip the hash
    const auto [it, added] = index_.emplace(key, static_cast<std::int32_t>(sets_.size()));
    if (added) sets_.push_back(make_(ma, mb, meff, reff));
    last_ = key, last_index_ = it->second;
    return it->second;
  }
  // A set of its own, not looked up (its index).
  std::int32_t add(int ma, int mb, double meff, double reff) {
    sets_.push_back(make_(ma, mb, meff, reff));
    return static_cast<std::int32_t>(sets_.size() - 1);
  }
  std::size_t size() const { return sets_.size(); }
  const ContactCoefficients* data() const { return sets_.data(); }

 private:
  struct Key {
    std::int32_t ma, mb;
    double meff, reff;
    bool operator==(const Key& o) const { return ma == o.ma && mb == o.mb && meff == o.meff && reff == o.reff; }
  };
  struct KeyHash {
    std::size_t operator()(const Key& k) const {
      std::uint64_t h = std::bit_cast<std::uint64_t>(k.meff) * 0x9E3779B97F4A7C15ULL;
      h ^= std::bit_cast<std::uint64_t>(k.reff) + 0x94D049BB133111EBULL + (h << 6) + (h >> 2);
      return h ^ (static_cast<std::uint64_t>(k.ma) << 32 | static_cast<std::uint32_t>(k.mb));
    }
  };
  std::vector<ContactCoefficients> sets_;
  std::unordered_map<Key, std::int32_t, KeyHash> index_;
  Key last_{-1, -1, 0, 0};
  std::int32_t last_index_ = -1;
  std::function<ContactCoefficients(int, int, double, double)> make_;
};

}  // namespace tessera
