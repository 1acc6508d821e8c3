// SPDX-License-Identifier: MIT
#include "core/h5_file.hpp"

#include "core/errors.hpp"

namespace tessera {

namespace {

template <class T>
hid_t h5_type();
template <>
hid_t h5_type<double>() {
  return H5T_NATIVE_DOUBLE;
}
template <>
hid_t h5_type<std::int64_t>() {
  return H5T_NATIVE_INT64;
}
template <>
hid_t h5_type<std::int32_t>() {
  return H5T_NATIVE_INT32;
}
template <>
hid_t h5_type<std::uint64_t>() {
  return H5T_NATIVE_UINT64;
}

void check(herr_t status, const std::string& what) {
  if (status < 0) throw RunError("HDF5: " + what + " failed");
}

}  // namespace

H5File H5File::create(const std::string& path, MPI_Comm comm) {
  hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
  H5Pset_fapl_mpio(fapl, comm, MPI_INFO_NULL);
  const hid_t f = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl);
  H5Pclose(fapl);
  if (f < 0) throw RunError("cannot create HDF5 file " + path);
  H5File h(f, comm);
  h.path_ = path;
  return h;
}

H5File H5File::open_read(const std::string& path, MPI_Comm comm) {
  hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
  H5Pset_fapl_mpio(fapl, comm, MPI_INFO_NULL);
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, fapl);
  H5Pclose(fapl);
  if (f < 0) throw InputError("restart", path, "a readable Tessera HDF5 checkpoint");
  H5File h(f, comm);
  h.path_ = path;
  return h;
}

H5File::H5File(H5File&& o) noexcept : file_(o.file_), comm_(o.comm_), path_(std::move(o.path_)) { o.file_ = -1; }

H5File::~H5File() { close(); }

void H5File::close() {
  if (file_ >= 0) H5Fclose(file_);
  file_ = -1;
}

template <class T>
long H5File::write_rows(const std::string& name, const T* data, std::size_t rows, int cols) {
  long mine = static_cast<long>(rows), offset = 0, total = 0;
  MPI_Exscan(&mine, &offset, 1, MPI_LONG, MPI_SUM, comm_);
  int rank = 0;
  MPI_Comm_rank(comm_, &rank);
  if (rank == 0) offset = 0;
  MPI_Allreduce(&mine, &total, 1, MPI_LONG, MPI_SUM, comm_);
  const int rank_dims = cols == 1 ? 1 : 2;
  hsize_t gdims[2] = {static_cast<hsize_t>(total), static_cast<hsize_t>(cols)};
  hsize_t ldims[2] = {static_cast<hsize_t>(rows), static_cast<hsize_t>(cols)};
  hsize_t start[2] = {static_cast<hsize_t>(offset), 0};
  const hid_t fspace = H5Screate_simple(rank_dims, gdims, nullptr);
  const hid_t dset = H5Dcreate2(file_, name.c_str(), h5_type<T>(), fspace, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  if (dset < 0) throw RunError("HDF5: cannot create dataset " + name + " in " + path_);
  const hid_t mspace = H5Screate_simple(rank_dims, ldims, nullptr);
  H5Sselect_hyperslab(fspace, H5S_SELECT_SET, start, nullptr, ldims, nullptr);
  if (rows == 0) {
    H5Sselect_none(fspace);
    H5Sselect_none(mspace);
  }
  const hid_t dxpl = H5Pcreate(H5P_DATASET_XFER);
  H5Pset_dxpl_mpio(dxpl, H5FD_MPIO_COLLECTIVE);
  const T dummy{};  // HDF5 rejects a null buffer even for an empty selection
  if (total > 0) check(H5Dwrite(dset, h5_type<T>(), mspace, fspace, dxpl, rows ? data : &dummy), "write " + name);
  H5Pclose(dxpl);
  H5Sclose(mspace);
  H5Sclose(fspace);
  H5Dclose(dset);
  return total;
}

template <class T>
std::vector<T> H5File::read_all(const std::string& name, int& cols) const {
  const hid_t dset = H5Dopen2(file_, name.c_str(), H5P_DEFAULT);
  if (dset < 0) throw InputError("restart", path_, "a checkpoint with dataset " + name);
  const hid_t space = H5Dget_space(dset);
  hsize_t dims[2] = {0, 1};
  const int nd = H5Sget_simple_extent_ndims(space);
  H5Sget_simple_extent_dims(space, dims, nullptr);
  cols = nd == 1 ? 1 : static_cast<int>(dims[1]);
  std::vector<T> out(static_cast<std::size_t>(dims[0]) * cols);
  if (!out.empty()) check(H5Dread(dset, h5_type<T>(), H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()), "read " + name);
  H5Sclose(space);
  H5Dclose(dset);
  return out;
}

void H5File::write_block(const std::string& name, const double* data, const std::size_t global[3],
                         const std::size_t offset[3], const std::size_t count[3], int comps) {
  const int nd = comps == 1 ? 3 : 4;
  hsize_t g[4] = {global[0], global[1], global[2], hsize_t(comps)};
  hsize_t o[4] = {offset[0], offset[1], offset[2], 0};
  hsize_t c[4] = {count[0], count[1], count[2], hsize_t(comps)};
  const hid_t fspace = H5Screate_simple(nd, g, nullptr);
  const hid_t dset = H5Dcreate2(file_, name.c_str(), H5T_NATIVE_DOUBLE, fspace, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  if (dset < 0) throw RunError("HDF5: cannot create dataset " + name + " in " + path_);
  const hid_t mspace = H5Screate_simple(nd, c, nullptr);
  H5Sselect_hyperslab(fspace, H5S_SELECT_SET, o, nullptr, c, nullptr);
  const hid_t dxpl = H5Pcreate(H5P_DATASET_XFER);
  H5Pset_dxpl_mpio(dxpl, H5FD_MPIO_COLLECTIVE);
  check(H5Dwrite(dset, H5T_NATIVE_DOUBLE, mspace, fspace, dxpl, data), "write " + name);
  H5Pclose(dxpl);
  H5Sclose(mspace);
  H5Sclose(fspace);
  H5Dclose(dset);
}

std::vector<double> H5File::read_block(const std::string& name, const std::size_t global[3],
                                       const std::size_t offset[3], const std::size_t count[3], int comps) const {
  const hid_t dset = H5Dopen2(file_, name.c_str(), H5P_DEFAULT);
  if (dset < 0) throw InputError("restart", path_, "a checkpoint with dataset " + name);
  const hid_t fspace = H5Dget_space(dset);
  const int nd = comps == 1 ? 3 : 4;
  hsize_t dims[4] = {0, 0, 0, 1};
  if (H5Sget_simple_extent_ndims(fspace) != nd)
    throw InputError("restart", path_, "dataset " + name + " of rank " + std::to_string(nd));
  H5Sget_simple_extent_dims(fspace, dims, nullptr);
  for (int d = 0; d < 3; ++d)
    if (dims[d] != global[d])
      throw InputError("restart", path_,
                       "a checkpoint on the same grid (dataset " + name + " has " + std::to_string(dims[d]) +
                           " cells along axis " + std::to_string(d) + ", the case " + std::to_string(global[d]) + ")");
  hsize_t o[4] = {offset[0], offset[1], offset[2], 0};
  hsize_t c[4] = {count[0], count[1], count[2], hsize_t(comps)};
  const hid_t mspace = H5Screate_simple(nd, c, nullptr);
  H5Sselect_hyperslab(fspace, H5S_SELECT_SET, o, nullptr, c, nullptr);
  std::vector<double> out(count[0] * count[1] * count[2] * comps);
  const hid_t dxpl = H5Pcreate(H5P_DATASET_XFER);
  H5Pset_dxpl_mpio(dxpl, H5FD_MPIO_COLLECTIVE);
  check(H5Dread(dset, H5T_NATIVE_DOUBLE, mspace, fspace, dxpl, out.data()), "read " + name);
  H5Pclose(dxpl);
  H5Sclose(mspace);
  H5Sclose(fspace);
  H5Dclose(dset);
  return out;
}

bool H5File::has(const std::string& name) const { return H5Lexists(file_, name.c_str(), H5P_DEFAULT) > 0; }
bool H5File::has_attribute(const std::string& name) const { return H5Aexists(file_, name.c_str()) > 0; }

void H5File::set_attribute(const std::string& name, double value) {
  const hid_t space = H5Screate(H5S_SCALAR);
  const hid_t a = H5Acreate2(file_, name.c_str(), H5T_NATIVE_DOUBLE, space, H5P_DEFAULT, H5P_DEFAULT);
  check(H5Awrite(a, H5T_NATIVE_DOUBLE, &value), "attribute " + name);
  H5Aclose(a);
  H5Sclose(space);
}

void H5File::set_attribute(const std::string& name, long value) {
  const hid_t space = H5Screate(H5S_SCALAR);
  const hid_t a = H5Acreate2(file_, name.c_str(), H5T_NATIVE_LONG, space, H5P_DEFAULT, H5P_DEFAULT);
  check(H5Awrite(a, H5T_NATIVE_LONG, &value), "attribute " + name);
  H5Aclose(a);
  H5Sclose(space);
}

void H5File::set_attribute(const std::string& name, const std::string& value) {
  const hid_t type = H5Tcopy(H5T_C_S1);
  H5Tset_size(type, value.size() + 1);
  const hid_t space = H5Screate(H5S_SCALAR);
  const hid_t a = H5Acreate2(file_, name.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT);
  check(H5Awrite(a, type, value.c_str()), "attribute " + name);
  H5Aclose(a);
  H5Sclose(space);
  H5Tclose(type);
}

double H5File::attribute_double(const std::string& name) const {
  double v = 0;
  const hid_t a = H5Aopen(file_, name.c_str(), H5P_DEFAULT);
  if (a < 0) throw InputError("restart", path_, "a checkpoint with attribute " + name);
  H5Aread(a, H5T_NATIVE_DOUBLE, &v);
  H5Aclose(a);
  return v;
}

long H5File::attribute_long(const std::string& name) const {
  long v = 0;
  const hid_t a = H5Aopen(file_, name.c_str(), H5P_DEFAULT);
  if (a < 0) throw InputError("restart", path_, "a checkpoint with attribute " + name);
  H5Aread(a, H5T_NATIVE_LONG, &v);
  H5Aclose(a);
  return v;
}

std::string H5File::attribute_string(const std::string& name) const {
  const hid_t a = H5Aopen(file_, name.c_str(), H5P_DEFAULT);
  if (a < 0) throw InputError("restart", path_, "a checkpoint with attribute " + name);
  const hid_t type = H5Aget_type(a);
  std::string s(H5Tget_size(type), '\0');
  H5Aread(a, type, s.data());
  H5Tclose(type);
  H5Aclose(a);
  while (!s.empty() && s.back() == '\0') s.pop_back();
  return s;
}

template long H5File::write_rows<double>(const std::string&, const double*, std::size_t, int);
template long H5File::write_rows<std::int64_t>(const std::string&, const std::int64_t*, std::size_t, int);
template long H5File::write_rows<std::int32_t>(const std::string&, const std::int32_t*, std::size_t, int);
template long H5File::write_rows<std::uint64_t>(const std::string&, const std::uint64_t*, std::size_t, int);
template std::vector<double> H5File::read_all<double>(const std::string&, int&) const;
template std::vector<std::int64_t> H5File::read_all<std::int64_t>(const std::string&, int&) const;
template std::vector<std::int32_t> H5File::read_all<std::int32_t>(const std::string&, int&) const;
template std::vector<std::uint64_t> H5File::read_all<std::uint64_t>(const std::string&, int&) const;

}  // namespace tessera
