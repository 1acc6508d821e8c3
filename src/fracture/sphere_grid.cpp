// SPDX-License-Identifier: MIT
#include "fracture/sphere_grid.hpp"

#include <algorithm>
#include <bit>
#include <cmath>

namespace tessera {

void SphereGrid::reset(double r_top, double r_small, double pad) {
  r_top_ = r_top, pad_ = pad;
  classes_ = 1;
  while (classes_ < kClasses && std::ldexp(r_top, -classes_) >= r_small) ++classes_;
  tables_.resize(static_cast<std::size_t>(classes_ * (classes_ + 1) / 2));
  for (int b = 0; b < classes_; ++b)
    for (int q = 0; q <= b; ++q) {
      Table& t = table(b, q);
      t.inv_width = 1 / (2 * std::ldexp(r_top, -q) + pad);
      t.entries.clear();
      std::fill(t.head.begin(), t.head.end(), -1);  // the buckets' storage is kept from run to run
    }
  live_ = dead_ = 0;
}

int SphereGrid::size_class(double r) const {
  int c = 0;
  while (c + 1 < classes_ && r <= std::ldexp(r_top_, -(c + 1))) ++c;
  return c;
}

void SphereGrid::cell(const Vec3& p, double inv_width, int c[3]) {
  constexpr double kFar = 1 << 30;  // a sphere flung this far shares the edge cells
  for (int d = 0; d < 3; ++d) c[d] = static_cast<int>(std::clamp(std::floor(p[d] * inv_width), -kFar, kFar));
}

void SphereGrid::rehash(Table& t, std::size_t buckets) {
  t.head.assign(buckets, -1);
  t.shift = 64 - std::countr_zero(buckets);
  for (std::size_t e = 0; e < t.entries.size(); ++e) {
    Entry& en = t.entries[e];
    int& h = t.head[hash(en.x, en.y, en.z) >> t.shift];
    en.next = h;
    h = static_cast<int>(e);
  }
}

void SphereGrid::insert(int s, const Vec3& p, double r) {
  const int b = size_class(r);
  if (where_.size() <= static_cast<std::size_t>(s)) where_.resize(static_cast<std::size_t>(s) + 1);
  ++live_;
  for (int q = 0; q <= b; ++q) {
    Table& t = table(b, q);
    if (2 * t.entries.size() >= t.head.size()) {  // at most one entry per two buckets
      rehash(t, std::max<std::size_t>(64, 2 * t.head.size()));
    }
    Entry en{s, -1, 0, 0, 0};
    int c[3];
    cell(p, t.inv_width, c);
    en.x = c[0], en.y = c[1], en.z = c[2];
    int& h = t.head[hash(en.x, en.y, en.z) >> t.shift];
    en.next = h;
    h = static_cast<int>(t.entries.size());
    where_[static_cast<std::size_t>(s)][static_cast<std::size_t>(q)] = h;
    t.entries.push_back(en);
  }
}

void SphereGrid::move(int s, const Vec3& p, double r) {
  const int b = size_class(r);
  for (int q = 0; q <= b; ++q)
    table(b, q).entries[static_cast<std::size_t>(where_[static_cast<std::size_t>(s)][static_cast<std::size_t>(q)])].sphere = -1;
  --live_, ++dead_;
  insert(s, p, r);
  if (4 * dead_ > live_ + 4096) compact();  // old entries lengthen the chains
}

void SphereGrid::compact() {
  for (int b = 0; b < classes_; ++b)
    for (int q = 0; q <= b; ++q) {
      Table& t = table(b, q);
      std::erase_if(t.entries, [](const Entry& en) { return en.sphere < 0; });
      for (std::size_t e = 0; e < t.entries.size(); ++e)
        where_[static_cast<std::size_t>(t.entries[e].sphere)][static_cast<std::size_t>(q)] = static_cast<int>(e);
      rehash(t, std::max<std::size_t>(64, t.head.size()));
    }
  dead_ = 0;
}

}  // namespace tessera
