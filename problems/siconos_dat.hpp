#pragma once
/// Import of Siconos numerics' text dumps (.dat) of friction-contact problems, read by our own
/// parser (Siconos' frictionContact_newFromFile allocates from declared counts unchecked).
///
/// The layout (Siconos' frictionContact_printInFile; numbers separated by any white space):
///   dimension d (2 or 3), numberOfContacts m,
///   the matrix W (a NumericsMatrix: storageType, size0, size1, then
///     0 dense:        size0 size1 again, then size0*size1 values in column-major order;
///     1 sparse block: nbblocks, blocknumber0, blocknumber1, the cumulative block sizes of rows and
///                     columns, filled1, filled2, the block-row pointers (index1_data) and block
///                     column indices (index2_data), then per block its number and its values in
///                     column-major order),
///   q (size0 values), mu (m values). Whatever follows mu is ignored, as Siconos' reader does
///   (its test files append solver settings there).
/// A global problem (GlobalFrictionContactProblem: d, m, M, H, q, b, mu) is recognised and
/// described, not imported. An LCP (linearComplementarity_printInFile: n, M, q) is imported by
/// read_siconos_dat_qp only. Storage 2 (CSparse's print, values with 6 significant digits) is
/// refused: it does not hold the problem to double precision.
///
/// Hostile files: every count is checked against the bytes that remain before anything is
/// allocated (each value takes at least two bytes), so memory is bounded by the file's size;
/// every error is an InputError "PATH: FIELD: problem (line L)", exit status 2.
#include "problems/fclib_io.hpp"
#include "problems/qpsnap.hpp"
#include "solvers/core/friction_problem.hpp"

#include <nlohmann/json.hpp>

#include <string>

namespace cb {

/// The local problem with its friction (W, q, mu) for the frictional solvers; dimension must be 3.
FrictionLocal read_siconos_dat_friction(const std::string& path);

/// The local problem's normal block as a QP, as FCLIB's local files are taken (fclib_io.hpp):
/// A = W_NN, b = -q_N, J = I, c = 0, x0 = 0. mu != 0 needs options.drop_friction (recorded in
/// meta.provenance); a W_NN not symmetric to 1e-12 max|W_NN| needs options.symmetrise. An LCP
/// (w = M z + q, 0 <= z ⊥ w >= 0) is the same with A = M, b = -q.
Qp read_siconos_dat_qp(const std::string& path, const FclibReadOptions& options = {});

/// A summary for `info`: local or global, dimension, contacts, storage, sizes, mu range, and
/// the commands that take the file. Reads (and so validates) the whole file.
nlohmann::json describe_siconos_dat(const std::string& path);

}  // namespace cb
