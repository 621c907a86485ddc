#pragma once
/// What a file holds, told by its content rather than its name, so that every command can name
/// the format of a file it cannot take and say how to convert it (instead of reading an HDF5
/// signature as a .qpsnap header length).
#include <string>

namespace cb {

enum class FileFormat {
    QPSNAP,                ///< 8-byte header length, then a JSON object
    FCLIB_GLOBAL,          ///< HDF5 holding /fclib_global
    FCLIB_LOCAL,           ///< HDF5 holding /fclib_local
    HDF5,                  ///< another HDF5 file (or FCLIB support not built)
    SICONOS_DAT,           ///< Siconos numerics' text dump of a (global) friction-contact problem (siconos_dat.hpp)
    MATRIX_MARKET_FOLDER,  ///< a folder with A.mtx (problems/matrix_market.hpp)
    MATRIX_MARKET_FILE,    ///< one .mtx file
    NPY,                   ///< one NumPy array
    FOLDER,                ///< another folder
    UNKNOWN,
};

/// Reads at most the first 2 KiB (and opens an HDF5 file to tell FCLIB's kinds apart). A FIFO,
/// device or missing path is an InputError naming it, never opened or waited on.
FileFormat sniff_format(const std::string& path);

/// "qpsnap", "FCLIB fclib_global (HDF5)", "Siconos .dat (numerics text)", ...
std::string format_name(FileFormat format);

/// Throws InputError("PATH: format: <format>, not a .qpsnap snapshot; <how to convert>") unless
/// the file is a .qpsnap or of unknown format (the snapshot reader then says what is wrong).
/// `command` names the command in the message ("solve").
void expect_qpsnap(const std::string& path, const std::string& command);

}  // namespace cb
