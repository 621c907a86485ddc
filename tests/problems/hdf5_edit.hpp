#pragma once
// Writes and replaces datasets of an HDF5 file with plain HDF5 calls, for the hostile FCLIB
// tests (tests/problems/test_fclib_io.cpp) and the FCLIB fuzz driver (tests/fuzz/fuzz_fclib.cpp):
// each builds malformed files (wrong lengths, types, ranks, unstored extents) that libfclib's
// writer never produces.
#include <hdf5.h>

#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

namespace cb::test {

class Hdf5Edit {
public:
    /// Opens PATH for writing, or creates it (truncating) when `create`; a created file is built
    /// in memory and written out once when closed (HDF5's core driver: the fuzz driver's speed).
    Hdf5Edit(const std::string& path, bool create)
    {
        H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
        const hid_t access = H5Pcreate(H5P_FILE_ACCESS);
        if (create) H5Pset_fapl_core(access, 1 << 16, 1);
        m_file = create ? H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, access)
                        : H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
        H5Pclose(access);
        if (m_file < 0) throw std::runtime_error("HDF5 cannot open " + path);
        m_links = H5Pcreate(H5P_LINK_CREATE);
        H5Pset_create_intermediate_group(m_links, 1);
    }
    ~Hdf5Edit()
    {
        H5Pclose(m_links);
        H5Fclose(m_file);
    }
    Hdf5Edit(const Hdf5Edit&) = delete;
    Hdf5Edit& operator=(const Hdf5Edit&) = delete;

    /// Removes the link NAME when it exists (its parents must exist for H5Lexists).
    void remove(const std::string& name)
    {
        if (H5Lexists(m_file, name.c_str(), H5P_DEFAULT) > 0) H5Ldelete(m_file, name.c_str(), H5P_DEFAULT);
    }

    /// NAME as a dataset of `values` with the given dimensions (empty: a scalar), replacing it.
    void put_ints(const std::string& name, const std::vector<long long>& values, std::vector<hsize_t> dims = {})
    {
        if (dims.empty() && values.size() != 1) dims = {hsize_t(values.size())};
        put(name, H5T_NATIVE_LLONG, values.data(), dims);
    }
    void put_reals(const std::string& name, const std::vector<double>& values, std::vector<hsize_t> dims = {})
    {
        if (dims.empty() && values.size() != 1) dims = {hsize_t(values.size())};
        put(name, H5T_NATIVE_DOUBLE, values.data(), dims);
    }
    /// A 1-D double dataset declaring `count` values with none written (its storage is empty).
    void put_unwritten(const std::string& name, hsize_t count)
    {
        remove_with_parents(name);
        const hid_t space = H5Screate_simple(1, &count, nullptr);
        const hid_t data =
            H5Dcreate2(m_file, name.c_str(), H5T_NATIVE_DOUBLE, space, m_links, H5P_DEFAULT, H5P_DEFAULT);
        if (data < 0) throw std::runtime_error("HDF5 cannot create " + name);
        H5Dclose(data);
        H5Sclose(space);
    }
    /// NAME as an external link to OBJECT in FILE (HDF5 resolves it only when it is traversed).
    void put_external_link(const std::string& name, const std::string& file, const std::string& object)
    {
        remove_with_parents(name);
        if (H5Lcreate_external(file.c_str(), object.c_str(), m_file, name.c_str(), m_links, H5P_DEFAULT) < 0)
            throw std::runtime_error("HDF5 cannot create the external link " + name);
    }
    /// A 1-D double dataset of `count` values stored in TARGET (external storage), none written:
    /// HDF5 opens TARGET only when the data are read.
    void put_external_storage(const std::string& name, hsize_t count, const std::string& target)
    {
        remove_with_parents(name);
        const hid_t create = H5Pcreate(H5P_DATASET_CREATE);
        H5Pset_external(create, target.c_str(), 0, count * sizeof(double));
        const hid_t space = H5Screate_simple(1, &count, nullptr);
        const hid_t data = H5Dcreate2(m_file, name.c_str(), H5T_NATIVE_DOUBLE, space, m_links, create, H5P_DEFAULT);
        H5Sclose(space);
        H5Pclose(create);
        if (data < 0) throw std::runtime_error("HDF5 cannot create " + name);
        H5Dclose(data);
    }
    /// NAME as a fixed-length string dataset (as H5LTmake_dataset_string writes).
    void put_text(const std::string& name, const std::string& text)
    {
        remove_with_parents(name);
        const hid_t type = H5Tcopy(H5T_C_S1);
        H5Tset_size(type, text.size() + 1);
        const hid_t space = H5Screate(H5S_SCALAR);
        const hid_t data = H5Dcreate2(m_file, name.c_str(), type, space, m_links, H5P_DEFAULT, H5P_DEFAULT);
        if (data < 0) throw std::runtime_error("HDF5 cannot create " + name);
        H5Dwrite(data, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, text.c_str());
        H5Dclose(data);
        H5Sclose(space);
        H5Tclose(type);
    }

private:
    /// Removes NAME when each of its parents exists (H5Lexists fails on a missing parent).
    void remove_with_parents(const std::string& name)
    {
        for (size_t slash = name.find('/', 1);; slash = name.find('/', slash + 1)) {
            const std::string prefix = name.substr(0, slash);
            if (H5Lexists(m_file, prefix.c_str(), H5P_DEFAULT) <= 0) return;
            if (slash == std::string::npos) break;
        }
        H5Ldelete(m_file, name.c_str(), H5P_DEFAULT);
    }

    void put(const std::string& name, hid_t type, const void* values, const std::vector<hsize_t>& dims)
    {
        remove_with_parents(name);
        const hid_t space =
            dims.empty() ? H5Screate(H5S_SCALAR) : H5Screate_simple(int(dims.size()), dims.data(), nullptr);
        const hid_t data = H5Dcreate2(m_file, name.c_str(), type, space, m_links, H5P_DEFAULT, H5P_DEFAULT);
        if (data < 0) throw std::runtime_error("HDF5 cannot create " + name);
        size_t count = 1;
        for (const hsize_t d : dims) count *= size_t(d);
        if (count > 0) H5Dwrite(data, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, values);
        H5Dclose(data);
        H5Sclose(space);
    }

    hid_t m_file = -1, m_links = -1;
};

}  // namespace cb::test
