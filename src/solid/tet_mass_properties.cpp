// SPDX-License-Identifier: MIT
#include "solid/tet_mass_properties.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <string>

#include "core/errors.hpp"

namespace tessera {

MassProperties tet_mass_properties(const std::vector<Vec3>& nodes, const std::vector<std::array<int, 4>>& tets,
                                   double density) {
  MassProperties mp;
  // First pass: volume and centroid; second: moments about the centroid (better conditioned than
  // moments about a far origin shifted afterwards).
  Vec3 first_moment;
  for (std::size_t t = 0; t < tets.size(); ++t) {
    const auto& e = tets[t];
    const Vec3 a = nodes.at(e[0]), b = nodes.at(e[1]), c = nodes.at(e[2]), d = nodes.at(e[3]);
    const double v = std::fabs(dot(b - a, cross(c - a, d - a))) / 6.0;
    if (!(v > 0.0)) throw InputError("shape.tetrahedra", std::to_string(t), "tetrahedra of positive volume");
    mp.volume += v;
    first_moment += (a + b + c + d) * (0.25 * v);
  }
  mp.centroid = first_moment / mp.volume;
  mp.mass = density * mp.volume;
  double S[3][3] = {};
  for (const auto& e : tets) {
    const Vec3 p[4] = {nodes[e[0]] - mp.centroid, nodes[e[1]] - mp.centroid, nodes[e[2]] - mp.centroid,
                       nodes[e[3]] - mp.centroid};
    const double v = std::fabs(dot(p[1] - p[0], cross(p[2] - p[0], p[3] - p[0]))) / 6.0;
    const Vec3 sum = p[0] + p[1] + p[2] + p[3];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        double s = sum[i] * sum[j];
        for (int k = 0; k < 4; ++k) s += p[k][i] * p[k][j];
        S[i][j] += v / 20.0 * s;
      }
  }
  const double trace = S[0][0] + S[1][1] + S[2][2];
  Eigen::Matrix3d I;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      mp.inertia[i][j] = density * ((i == j ? trace : 0.0) - S[i][j]);
      I(i, j) = mp.inertia[i][j];
    }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(I);
  Eigen::Matrix3d axes = eig.eigenvectors();
  if (axes.determinant() < 0) axes.col(2) *= -1.0;  // a rotation, not a reflection
  for (int k = 0; k < 3; ++k) {
    mp.principal_moments[k] = eig.eigenvalues()(k);
    mp.principal_axes[k] = {axes(0, k), axes(1, k), axes(2, k)};
  }
  return mp;
}

}  // namespace tessera
