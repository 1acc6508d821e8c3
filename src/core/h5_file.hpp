// SPDX-License-Identifier: MIT
// Parallel HDF5 (MPI-IO) files holding row-distributed datasets: each rank writes its rows at the
// offset given by an exclusive scan of the row counts, collectively. Readers may read a whole
// dataset on every rank (checkpoints of up to a few million bodies).
#pragma once
#include <hdf5.h>
#include <mpi.h>

#include <cstdint>
#include <string>
#include <vector>

namespace tessera {

class H5File {
 public:
  static H5File create(const std::string& path, MPI_Comm comm);
  static H5File open_read(const std::string& path, MPI_Comm comm);
  ~H5File();
  H5File(H5File&& o) noexcept;
  H5File(const H5File&) = delete;
  H5File& operator=(const H5File&) = delete;
  H5File& operator=(H5File&&) = delete;

  // Collective. Writes `rows` rows of `cols` values from this rank; returns the global row count.
  template <class T>
  long write_rows(const std::string& name, const T* data, std::size_t rows, int cols);
  // Reads a whole dataset on every rank; cols receives its second dimension (1 for 1-D).
  template <class T>
  std::vector<T> read_all(const std::string& name, int& cols) const;
  bool has(const std::string& name) const;
  bool has_attribute(const std::string& name) const;
  // Collective. A block of a global array of shape (global[0], global[1], global[2], comps) in C
  // order (slowest first): this rank writes count[] rows from offset[] of its packed buffer
  // (count[0] * count[1] * count[2] * comps values). Fluid fields use (z, y, x, comps).
  void write_block(const std::string& name, const double* data, const std::size_t global[3],
                   const std::size_t offset[3], const std::size_t count[3], int comps);
  // Reads this rank's block of such an array (checks the global shape).
  std::vector<double> read_block(const std::string& name, const std::size_t global[3], const std::size_t offset[3],
                                 const std::size_t count[3], int comps) const;

  void set_attribute(const std::string& name, double value);
  void set_attribute(const std::string& name, long value);
  void set_attribute(const std::string& name, const std::string& value);
  double attribute_double(const std::string& name) const;
  long attribute_long(const std::string& name) const;
  std::string attribute_string(const std::string& name) const;
  void close();

 private:
  H5File(hid_t file, MPI_Comm comm) : file_(file), comm_(comm) {}
  hid_t file_ = -1;
  MPI_Comm comm_;
  std::string path_;
};

}  // namespace tessera
