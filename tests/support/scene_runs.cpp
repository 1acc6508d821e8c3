// SPDX-License-Identifier: MIT
#include "support/scene_runs.hpp"

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "app/dem_scene.hpp"

namespace tessera::test {

int world_rank() {
  int r = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &r);
  return r;
}

int world_size() {
  int s = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &s);
  return s;
}

nlohmann::json run_case_on(int ranks, const std::string& yaml, const std::vector<std::string>& sets,
                           const std::string& output_dir, std::optional<std::string> restart,
                           const std::function<void(Scene&, MPI_Comm)>& after) {
  MPI_Comm sub = MPI_COMM_NULL;
  MPI_Comm_split(MPI_COMM_WORLD, world_rank() < ranks ? 0 : MPI_UNDEFINED, world_rank(), &sub);
  nlohmann::json summary;
  if (sub != MPI_COMM_NULL) {
    {
      Config c = Config::parse(yaml, sets);
      auto scene = make_scene(c.root(), sub, ".");
      c.check_unused();
      RunOptions opt;
      opt.output_dir = output_dir;
      opt.quiet = true;
      opt.restart = restart;
      if (world_rank() == 0) std::filesystem::create_directories(output_dir);
      MPI_Barrier(sub);
      summary = scene->run(opt, {});
      if (after) after(*scene, sub);
    }
    MPI_Comm_free(&sub);
  }
  MPI_Barrier(MPI_COMM_WORLD);
  return summary;
}

BodyStates run_scene_on(int ranks, const std::string& yaml, const std::vector<std::string>& sets,
                        const std::string& output_dir, std::optional<std::string> restart) {
  BodyStates states;
  run_case_on(ranks, yaml, sets, output_dir, restart, [&](Scene& scene, MPI_Comm sub) {
    const ParticleStore& p = dynamic_cast<DemScene&>(scene).dem().particles();
    std::vector<double> mine;
    for (std::size_t i = 0; i < p.owned; ++i) p.pack(i, mine);
    const int stride = p.packed_size();
    int n = static_cast<int>(mine.size()), size = 1;
    MPI_Comm_size(sub, &size);
    std::vector<int> counts(size), displs(size, 0);
    MPI_Gather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, sub);
    std::vector<double> all;
    if (world_rank() == 0) {
      for (int r = 1; r < size; ++r) displs[r] = displs[r - 1] + counts[r - 1];
      all.resize(displs[size - 1] + counts[size - 1]);
    }
    MPI_Gatherv(mine.data(), n, MPI_DOUBLE, all.data(), counts.data(), displs.data(), MPI_DOUBLE, 0, sub);
    for (std::size_t off = 0; off < all.size(); off += stride)
      states[static_cast<long>(all[off])] = std::vector<double>(all.begin() + off, all.begin() + off + stride);
  });
  return states;
}

long count_differences(const BodyStates& a, const BodyStates& b, const char* what) {
  long diff = 0;
  for (const auto& [id, s] : a) {
    const auto it = b.find(id);
    const bool same = it != b.end() && it->second.size() == s.size() &&
                      std::memcmp(it->second.data(), s.data(), s.size() * sizeof(double)) == 0;
    if (!same && ++diff <= 3) {
      std::printf("  %s: body %ld differs", what, id);
      if (it != b.end()) std::printf(" (x %.17g vs %.17g)", s[6], it->second[6]);
      std::printf("\n");
    }
  }
  return diff + static_cast<long>(b.size() > a.size() ? b.size() - a.size() : 0);
}

std::string last_file(const std::string& dir, const std::string& ext) {
  std::string last;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.path().extension() == ext && e.path().string() > last) last = e.path().string();
  return last;
}

std::string file_text(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace tessera::test
