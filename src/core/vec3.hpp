// SPDX-License-Identifier: MIT
// Small fixed-size 3-vector for kernels and set-up code. Hot data is stored as contiguous arrays of
// doubles (x0 y0 z0 x1 y1 z1 ...); Vec3 is the value type kernels load into and compute with.
#pragma once
#include <cmath>

namespace tessera {

struct Vec3 {
  double x = 0, y = 0, z = 0;

  static Vec3 load(const double* p) { return {p[0], p[1], p[2]}; }
  void store(double* p) const { p[0] = x, p[1] = y, p[2] = z; }
  void add_to(double* p) const { p[0] += x, p[1] += y, p[2] += z; }
  void subtract_from(double* p) const { p[0] -= x, p[1] -= y, p[2] -= z; }

  double operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  double& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
  Vec3 operator+(const Vec3& o) const { return {x + o.x, y + o.y, z + o.z}; }
  Vec3 operator-(const Vec3& o) const { return {x - o.x, y - o.y, z - o.z}; }
  Vec3 operator-() const { return {-x, -y, -z}; }
  Vec3 operator*(double s) const { return {x * s, y * s, z * s}; }
  Vec3 operator/(double s) const { return {x / s, y / s, z / s}; }
  Vec3& operator+=(const Vec3& o) {
    x += o.x, y += o.y, z += o.z;
    return *this;
  }
  Vec3& operator-=(const Vec3& o) {
    x -= o.x, y -= o.y, z -= o.z;
    return *this;
  }
  Vec3& operator*=(double s) {
    x *= s, y *= s, z *= s;
    return *this;
  }
};

inline Vec3 operator*(double s, const Vec3& v) { return v * s; }
inline double dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline Vec3 hadamard(const Vec3& a, const Vec3& b) { return {a.x * b.x, a.y * b.y, a.z * b.z}; }
inline double norm2(const Vec3& a) { return dot(a, a); }
inline double norm(const Vec3& a) { return std::sqrt(dot(a, a)); }

}  // namespace tessera
