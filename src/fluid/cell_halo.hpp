// SPDX-License-Identifier: MIT
// The ghost exchange of arrays laid out over a rank's ghosted box of a Cartesian process grid
// (the flow fields, FluidGrid; the multigrid's levels, CellMultigrid; docs/theory.md F11a).
//
// Each rank sends every neighbour rank whose ghosts image its owned cells those cells, `width`
// layers deep, all boxes for one rank in one message, and writes what it receives into its ghost
// layers; where the neighbour along a periodic direction is the rank itself, it copies its own far
// layers. With the star stencil (face ghosts only) the six faces go in one round, all messages in
// flight together. With the box stencil, direction by direction (x, then y, then z): the layers
// sent along a later direction include the ghosts the earlier directions filled (where a neighbour
// rank or periodic image exists along them), so edges and corners arrive in two or three hops.
// A ghost beyond a wall or an outflow is never written, as in a PETSc DMDA's DMLocalToLocal with
// DM_BOUNDARY_GHOSTED, which this replaces: that one's scatter also copied every owned value onto
// itself through an index list, which cost the flow a tenth of its time on 2 ranks
// (docs/performance.md, 2026-12-03). Several fields go in the same messages.
#pragma once
#include <mpi.h>

#include <array>
#include <initializer_list>
#include <vector>

namespace tessera {

class CellHalo {
 public:
  enum class Stencil { star, box };
  // A rank's block: process grid and this rank's coordinates in it (rank = a + procs[0] (b +
  // procs[1] c) on `comm`, a DMDA's order), the owned box [s, s + m) and the ghosted box
  // [gs, gs + gm) in global cell indices, x fastest in memory.
  struct Block {
    std::array<int, 3> procs{}, coords{};
    std::array<bool, 3> periodic{};
    std::array<int, 3> s{}, m{}, gs{}, gm{};
  };
  CellHalo(MPI_Comm comm, const Block& block, int width, Stencil stencil);
  ~CellHalo();
  CellHalo(const CellHalo&) = delete;
  CellHalo& operator=(const CellHalo&) = delete;

  // False where no ghost has a source (one rank, nothing periodic): exchange() does nothing.
  bool active() const { return active_; }
  // Whether an exchange fills the ghost layers on `side` (0 low, 1 high) of direction d (a
  // neighbour rank or a periodic image lies there; not a wall or an outflow).
  bool fills(int d, int side) const { return fills_[d][side]; }
  // Fills the ghosts of every field (collective over the communicator); single-precision fields
  // travel as doubles (exactly).
  void exchange(std::initializer_list<std::vector<double>*> fields) const { exchange_fields(fields); }
  void exchange(std::initializer_list<std::vector<float>*> fields) const { exchange_fields(fields); }

  // What this rank has sent since the halo was made: messages to other ranks and their bytes (a
  // periodic copy onto itself is not a message).
  struct Traffic {
    long messages = 0;
    double bytes = 0;
    Traffic& operator+=(const Traffic& o) {
      messages += o.messages, bytes += o.bytes;
      return *this;
    }
  };
  const Traffic& traffic() const { return traffic_; }

 private:
  // A box of local (ghosted-array) indices [lo, hi).
  struct Box {
    std::array<int, 3> lo{}, hi{};
    std::size_t size() const { return std::size_t(hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]); }
  };
  // A neighbour rank (or this rank, for a periodic image of itself): the owned boxes it is sent,
  // and the ghost boxes its message fills, each list in the sender's order of the offsets.
  struct Peer {
    int rank = -1;
    std::vector<Box> send, recv;
    std::size_t send_size = 0, recv_size = 0;  // cells, all boxes
  };
  template <class F>
  void for_rows(const Box& b, F&& fn) const;
  template <class T>
  void pack(const Box& b, const std::vector<T>& f, double* out) const;
  template <class T>
  void unpack(const Box& b, std::vector<T>& f, const double* in) const;
  template <class T>
  void exchange_fields(std::initializer_list<std::vector<T>*> fields) const;

  MPI_Comm comm_ = MPI_COMM_NULL;
  int me_ = 0;
  bool active_ = false;
  std::array<std::ptrdiff_t, 3> stride_{};
  std::array<std::array<bool, 2>, 3> fills_{};
  // The exchange's rounds, one after the other (star: one; box: one per direction), each a list of
  // peers whose messages are in flight together: other ranks first, then this rank's own images.
  std::vector<std::vector<Peer>> rounds_;
  mutable std::vector<std::vector<double>> send_buf_, recv_buf_;
  mutable std::vector<MPI_Request> requests_;
  mutable Traffic traffic_;
};

}  // namespace tessera
