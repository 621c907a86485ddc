#pragma once
/// Matrix Market interop (https://math.nist.gov/MatrixMarket/formats.html): a QP as a folder
///   A.mtx   coordinate real general, n x n, both triangles (symmetric and integer files read too)
///   b.mtx x0.mtx c.mtx   array real general, k x 1 (coordinate k x 1 and 1 x k read too)
///   J.mtx   coordinate real general, m x n ("0 n 0" when m = 0)
///   meta.json (optional), contact.json (optional: {"kind": [m], "depth": [m], "vertex": [[4] x m]}),
///   x_ref.mtx, lambda_ref.mtx (optional)
///   mu.mtx T.mtx cT.mtx h.mtx v0.mtx (optional: Coulomb friction, snapshot version 2's fields, with
///   its rules: mu (m) with T (2m x n, coordinate), cT (2m) only with T, h (1 x 1) and v0 (n) with h)
/// Values are written with %.17g, so .qpsnap -> folder -> .qpsnap is bit-exact in the arrays, friction
/// included.
#include "problems/qpsnap.hpp"

#include <string>

namespace cb {

/// A sparse matrix from a .mtx file (coordinate or array; real or integer; general or
/// symmetric, symmetric expanded). Rows sorted; duplicates are an InputError naming the line.
SpMat read_mtx_matrix(const std::string& path);

/// A vector from a .mtx file: array k x 1 (or 1 x k), or coordinate k x 1 / 1 x k. With
/// `expected_size` >= 0 a size line declaring more entries is refused before anything is
/// allocated ("size: expected 12 entries (n of the snapshot), got 300000000"; `what` names the
/// snapshot's dimension).
Vec read_mtx_vector(const std::string& path, long expected_size = -1, const std::string& what = "");

/// Coordinate real general, 1-based, every stored entry (both triangles of A).
void write_mtx_matrix(const std::string& path, const SpMat& M, const std::string& comment = "");

/// Array real general, size x 1.
void write_mtx_vector(const std::string& path, const Vec& v, const std::string& comment = "");

/// Reads a folder and runs the same validation as read_qpsnap (validate_qp).
Qp read_matrix_market_folder(const std::string& dir, SnapshotExtras* extras = nullptr);

/// Writes the folder atomically: DIR.tmp.<pid> first, then renamed to DIR. An existing DIR is
/// replaced only if it holds an A.mtx (i.e. looks like a snapshot folder).
void write_matrix_market_folder(const std::string& dir, const Qp& qp, const SnapshotExtras* extras = nullptr);

}  // namespace cb
