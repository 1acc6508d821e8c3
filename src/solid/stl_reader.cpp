// SPDX-License-Identifier: MIT
#include "solid/stl_reader.hpp"

#include <array>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "core/errors.hpp"

namespace tessera {

namespace {

struct Builder {
  TetMesh mesh;
  std::map<std::array<double, 3>, int> index;
  double scale;
  int node(double x, double y, double z) {
    const auto [it, added] = index.emplace(std::array<double, 3>{x, y, z}, static_cast<int>(mesh.nodes.size()));
    if (added) mesh.nodes.push_back(Vec3{x, y, z} * scale);
    return it->second;
  }
};

}  // namespace

TetMesh read_stl(const std::string& path, double scale) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError("mesh", path, "a readable STL file");
  const auto size = std::filesystem::file_size(path);
  Builder b{{}, {}, scale};
  // Binary: an 80-byte header, a 32-bit triangle count, 50 bytes per triangle. Some exporters
  // start binary headers with "solid", so the size decides, not the first word.
  char header[84] = {};
  in.read(header, 84);
  std::uint32_t count = 0;
  std::memcpy(&count, header + 80, 4);
  if (in && size == 84 + 50ull * count) {
    for (std::uint32_t t = 0; t < count; ++t) {
      char rec[50];
      in.read(rec, 50);
      float v[12];
      std::memcpy(v, rec, 48);
      b.mesh.triangles.push_back({b.node(v[3], v[4], v[5]), b.node(v[6], v[7], v[8]), b.node(v[9], v[10], v[11])});
    }
    if (!in) throw InputError("mesh", path, "a complete binary STL file");
    return b.mesh;
  }
  in.clear();
  in.seekg(0);
  std::string word;
  in >> word;
  if (word != "solid") throw InputError("mesh", path, "an STL file (ASCII starting with 'solid', or binary)");
  std::array<int, 3> tri{};
  int corner = 0;
  while (in >> word) {
    if (word == "vertex") {
      double x = 0, y = 0, z = 0;
      if (!(in >> x >> y >> z)) throw InputError("mesh", path, "'vertex x y z' lines");
      if (corner > 2) throw InputError("mesh", path, "facets of three vertices");
      tri[corner++] = b.node(x, y, z);
    } else if (word == "endloop") {
      if (corner != 3) throw InputError("mesh", path, "facets of three vertices");
      b.mesh.triangles.push_back(tri);
      corner = 0;
    }
  }
  if (b.mesh.triangles.empty()) throw InputError("mesh", path, "at least one facet");
  return b.mesh;
}

}  // namespace tessera
