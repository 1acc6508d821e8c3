// SPDX-License-Identifier: MIT
#include "solid/gmsh_reader.hpp"

#include <fstream>
#include <sstream>
#include <unordered_map>

#include "core/errors.hpp"

namespace tessera {

namespace {

class Reader {
 public:
  explicit Reader(const std::string& path) : path_(path), in_(path) {
    if (!in_) throw InputError("mesh", path, "a readable Gmsh .msh file");
  }
  std::string line() {
    std::string l;
    if (!std::getline(in_, l)) fail("unexpected end of file");
    ++line_no_;
    if (!l.empty() && l.back() == '\r') l.pop_back();
    return l;
  }
  bool next(std::string& l) {
    if (!std::getline(in_, l)) return false;
    ++line_no_;
    if (!l.empty() && l.back() == '\r') l.pop_back();
    return true;
  }
  template <class... T>
  void parse(const std::string& l, T&... values) {
    std::istringstream s(l);
    if (!(s >> ... >> values)) fail("cannot read '" + l + "'");
  }
  [[noreturn]] void fail(const std::string& why) const {
    throw InputError("mesh", path_ + ":" + std::to_string(line_no_), "a Gmsh MSH 2.2 or 4.1 ASCII file (" + why + ")");
  }
  void skip_to(const std::string& end) {
    std::string l;
    while (next(l))
      if (l == end) return;
    fail("missing " + end);
  }

 private:
  std::string path_;
  std::ifstream in_;
  long line_no_ = 0;
};

// MSH 4.1 sections: "numBlocks numItems minTag maxTag", then per block
// "entityDim entityTag kind numItemsInBlock" (kind: parametric flag for nodes, type for elements).
struct Block {
  int dim = 0, entity = 0, kind = 0;
  long count = 0;
};
long read_block_count(Reader& r) {
  long blocks = 0, count = 0, min_tag = 0, max_tag = 0;
  r.parse(r.line(), blocks, count, min_tag, max_tag);
  return blocks;
}
Block read_block(Reader& r) {
  Block b;
  r.parse(r.line(), b.dim, b.entity, b.kind, b.count);
  return b;
}

int index_of(const std::unordered_map<long, int>& map, long tag, Reader& r) {
  const auto it = map.find(tag);
  if (it == map.end()) r.fail("element refers to unknown node " + std::to_string(tag));
  return it->second;
}

}  // namespace

TetMesh read_gmsh(const std::string& path) {
  Reader r(path);
  TetMesh mesh;
  std::unordered_map<long, int> node_index;
  double version = 0;
  std::string l;
  while (r.next(l)) {
    if (l == "$MeshFormat") {
      int binary = 0, size = 0;
      r.parse(r.line(), version, binary, size);
      if (binary != 0) r.fail("binary files are not read; save as ASCII");
      if (version < 2.0 || version >= 5.0 || (version >= 3.0 && version < 4.1))
        r.fail("version " + std::to_string(version));
      r.skip_to("$EndMeshFormat");
    } else if (l == "$Nodes") {
      if (version >= 4.1) {
        for (long blocks = read_block_count(r); blocks > 0; --blocks) {
          const Block block = read_block(r);
          std::vector<long> tags(static_cast<std::size_t>(block.count));
          for (auto& t : tags) r.parse(r.line(), t);
          for (const long t : tags) {
            Vec3 x;
            r.parse(r.line(), x.x, x.y, x.z);  // parametric coordinates, if any, follow and are ignored
            node_index[t] = static_cast<int>(mesh.nodes.size());
            mesh.nodes.push_back(x);
          }
        }
      } else {
        long count = 0;
        r.parse(r.line(), count);
        for (long k = 0; k < count; ++k) {
          long t = 0;
          Vec3 x;
          r.parse(r.line(), t, x.x, x.y, x.z);
          node_index[t] = static_cast<int>(mesh.nodes.size());
          mesh.nodes.push_back(x);
        }
      }
      r.skip_to("$EndNodes");
    } else if (l == "$Elements") {
      auto add = [&](int type, const std::vector<long>& nodes) {
        if (type == 4) {
          mesh.tetrahedra.push_back({index_of(node_index, nodes[0], r), index_of(node_index, nodes[1], r),
                                     index_of(node_index, nodes[2], r), index_of(node_index, nodes[3], r)});
        } else if (type == 2) {
          mesh.triangles.push_back({index_of(node_index, nodes[0], r), index_of(node_index, nodes[1], r),
                                    index_of(node_index, nodes[2], r)});
        }
      };
      auto nodes_of = [](int type) { return type == 4 ? 4 : type == 2 ? 3 : type == 1 ? 2 : type == 15 ? 1 : -1; };
      if (version >= 4.1) {
        for (long blocks = read_block_count(r); blocks > 0; --blocks) {
          const Block block = read_block(r);
          const int type = block.kind, nn = nodes_of(type);
          for (long e = 0; e < block.count; ++e) {
            const std::string el = r.line();
            if (nn < 0) continue;  // an element type shapes do not use
            std::istringstream s(el);
            long tag = 0;
            std::vector<long> nodes(static_cast<std::size_t>(nn));
            s >> tag;
            for (auto& v : nodes) s >> v;
            if (!s) r.fail("cannot read element '" + el + "'");
            add(type, nodes);
          }
        }
      } else {
        long count = 0;
        r.parse(r.line(), count);
        for (long e = 0; e < count; ++e) {
          const std::string el = r.line();
          std::istringstream s(el);
          long tag = 0;
          int type = 0, ntags = 0;
          s >> tag >> type >> ntags;
          for (int k = 0; k < ntags; ++k) s >> tag;
          const int nn = nodes_of(type);
          if (nn < 0) continue;
          std::vector<long> nodes(static_cast<std::size_t>(nn));
          for (auto& v : nodes) s >> v;
          if (!s) r.fail("cannot read element '" + el + "'");
          add(type, nodes);
        }
      }
      r.skip_to("$EndElements");
    }
  }
  if (version == 0) r.fail("no $MeshFormat section");
  if (mesh.nodes.empty()) r.fail("no nodes");
  return mesh;
}

}  // namespace tessera
