// SPDX-License-Identifier: MIT
// Spheres of many sizes in cells sized by class (docs/theory.md B6a): the contact list's search.
//
// A graded mesh carries contact spheres from a fraction of a millimetre at the hole to centimetres
// far from it. One grid of cells sized by the largest (2 r_max + pad) makes every small sphere
// test the thousands of small spheres within 2 r_max of it. Here class L holds the radii in
// (r_top / 2^(L+1), r_top / 2^L] (the last class everything smaller), and the spheres of class L
// are indexed in cells of width w_Q = 2 r_top / 2^Q + pad for every Q <= L. A sphere of radius r
// (class A) meets a sphere of class B within r + r_B + pad <= w_min(A,B): it finds all of them in
// the 27 cells around it in class B's grid of width w_min(A,B). Each class's cells are a hash
// table (a flung element does not grow a dense grid), each entry keeps its cell so a hash
// collision reports nothing twice: a query reports every sphere of the grid within its reach
// exactly once, and others (the caller tests the distance). A sphere can be moved (its old entries
// are marked and skipped, and dropped when they outnumber the live ones).
#pragma once
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "core/vec3.hpp"

namespace tessera {

class SphereGrid {
 public:
  // Empties the grid. Radii up to r_top are accepted; classes down to r_small (at most kClasses);
  // pad: what every query's reach adds to the two radii (skin and margins).
  void reset(double r_top, double r_small, double pad);
  // Sphere s (an id >= 0, not in the grid) at p with radius r <= r_top.
  void insert(int s, const Vec3& p, double r);
  // Sphere s, in the grid with radius r, now at p.
  void move(int s, const Vec3& p, double r);
  int size_class(double r) const;
  // f(b) for every sphere b within r + r_b + pad of p, each once, and possibly some farther.
  // coarser_only: only the spheres of p's class and the larger ones (a build finds each pair once,
  // from its smaller sphere; within one class the caller keeps one of the two).
  template <class F>
  void near(const Vec3& p, double r, bool coarser_only, F&& f) const {
    const int a = size_class(r);
    for (int b = 0; b < classes_; ++b) {
      if (coarser_only && b > a) break;
      const Table& t = table(b, b < a ? b : a);
      if (t.entries.empty()) continue;
      // The cells that the cube of half-width r + r_b + pad around p meets (2 or 3 per direction).
      const double reach = r + std::ldexp(r_top_, -b) + pad_;
      int lo[3], hi[3];
      cell(p - Vec3{reach, reach, reach}, t.inv_width, lo);
      cell(p + Vec3{reach, reach, reach}, t.inv_width, hi);
      for (int z = lo[2]; z <= hi[2]; ++z)
        for (int y = lo[1]; y <= hi[1]; ++y)
          for (int x = lo[0]; x <= hi[0]; ++x)
            for (int e = t.head[hash(x, y, z) >> t.shift]; e >= 0;) {
              const Entry& en = t.entries[static_cast<std::size_t>(e)];
              if (en.x == x && en.y == y && en.z == z && en.sphere >= 0) f(en.sphere);
              e = en.next;
            }
    }
  }

  static constexpr int kClasses = 8;

 private:
  struct Entry {
    int sphere, next, x, y, z;
  };
  struct Table {
    double inv_width = 1;
    int shift = 64;         // a bucket is the hash's top 64 - shift bits
    std::vector<int> head;  // power-of-two buckets, at least twice the entries
    std::vector<Entry> entries;
  };
  // Fibonacci hashing of the packed cell: the top bits of a 64-bit product mix all three coordinates.
  static std::uint64_t hash(int x, int y, int z) {
    const std::uint64_t k = (static_cast<std::uint64_t>(static_cast<std::uint32_t>(x)) << 42) ^
                            (static_cast<std::uint64_t>(static_cast<std::uint32_t>(y)) << 21) ^
                            static_cast<std::uint64_t>(static_cast<std::uint32_t>(z));
    return k * 0x9E3779B97F4A7C15ull;
  }
  static void cell(const Vec3& p, double inv_width, int c[3]);
  static void rehash(Table& t, std::size_t buckets);
  void compact();  // drops the moved spheres' old entries
  // Class b's spheres in cells of class q's width (q <= b).
  const Table& table(int b, int q) const { return tables_[static_cast<std::size_t>(b * (b + 1) / 2 + q)]; }
  Table& table(int b, int q) { return tables_[static_cast<std::size_t>(b * (b + 1) / 2 + q)]; }

  double r_top_ = 0, pad_ = 0;
  int classes_ = 1;
  std::vector<Table> tables_;
  std::vector<std::array<int, kClasses>> where_;  // each sphere's entry in each of its tables
  std::size_t live_ = 0, dead_ = 0;
};

}  // namespace tessera
