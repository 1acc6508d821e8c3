// SPDX-License-Identifier: MIT
// Tangential contact history keyed by the permanent order keys of the two bodies (lower first; see
// ParticleStore::order), so that it survives neighbour-list rebuilds, migration between ranks and
// restarts. The key packs two 32-bit values; keys and ids are below 2^32 (checked at creation).
#pragma once
#include <array>
#include <cstdint>
#include <unordered_map>

namespace tessera {

using PairKey = std::uint64_t;
using HistoryMap = std::unordered_map<PairKey, std::array<double, 3>>;

inline PairKey pair_key(std::int64_t a, std::int64_t b) {
  const auto lo = static_cast<std::uint64_t>(a < b ? a : b);
  const auto hi = static_cast<std::uint64_t>(a < b ? b : a);
  return (lo << 32) | hi;
}
inline std::int64_t key_low(PairKey k) { return static_cast<std::int64_t>(k >> 32); }
inline std::int64_t key_high(PairKey k) { return static_cast<std::int64_t>(k & 0xffffffffULL); }

constexpr std::int64_t kMaxBodyId = (std::int64_t{1} << 32) - 1;

// Wall contacts of contact spheres keep their history in the same maps: key (element key, base +
// wall slot). Element keys must stay below the base.
constexpr std::int64_t kWallKeyBase = (std::int64_t{1} << 32) - 1024;
inline PairKey wall_key(std::int64_t element_key, int slot) {
  return (static_cast<PairKey>(element_key) << 32) | static_cast<PairKey>(kWallKeyBase + slot);
}
// Mesh-wall contacts: (element key, base + 256 + 8 mesh + ordinal of the contact with that mesh).
// Wall slots stay below 256 (planes and boxes), meshes below kMaxMeshWalls. Free-sphere contacts
// (free_spheres.hpp): (element key, base + 960 + sphere), spheres below kMaxFreeSpheres; they
// travel with the element like mesh springs (is_mesh_key holds for both).
constexpr int kMaxWallSlots = 256, kMaxMeshWalls = 88, kMeshContactsPerSphere = 8, kMaxFreeSpheres = 64;
inline PairKey mesh_key(std::int64_t element_key, int mesh, int ordinal) {
  return (static_cast<PairKey>(element_key) << 32) |
         static_cast<PairKey>(kWallKeyBase + kMaxWallSlots + kMeshContactsPerSphere * mesh + ordinal);
}
inline PairKey free_sphere_key(std::int64_t element_key, int sphere) {
  return (static_cast<PairKey>(element_key) << 32) |
         static_cast<PairKey>(kWallKeyBase + kMaxWallSlots + kMeshContactsPerSphere * kMaxMeshWalls + sphere);
}
// The spring stored under key, or zero (a new contact).
inline std::array<double, 3> spring_or_zero(const HistoryMap& h, PairKey key) {
  const auto it = h.find(key);
  return it == h.end() ? std::array<double, 3>{0, 0, 0} : it->second;
}
inline bool is_mesh_key(PairKey k) { return key_high(k) >= kWallKeyBase + kMaxWallSlots; }
inline bool is_free_sphere_key(PairKey k) {
  return key_high(k) >= kWallKeyBase + kMaxWallSlots + kMeshContactsPerSphere * kMaxMeshWalls;
}
static_assert(kMaxWallSlots + kMeshContactsPerSphere * kMaxMeshWalls + kMaxFreeSpheres <= 1024);

}  // namespace tessera
