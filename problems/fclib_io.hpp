#pragma once
/// FCLIB (HDF5) export and import of the contact QP as a frictionless `fclib_global` problem.
/// Ref: FCLIB, fclib.h (the global problem  M v = H r + f,  u = H'v + w,  C*_mu ∋ u ⊥ r ∈ C_mu).
///
/// Mapping (exact, so a write/read round trip is bit for bit): v = x, M = A, f = b, spacedim 3,
/// one contact per row i of J with mu_i = 0; H is n x 3m with column 3i = row i of J (the normal)
/// and columns 3i+1, 3i+2 (the tangents) empty; w = (-c_i, 0, 0) per contact. With mu = 0 the
/// cone condition reads r_N = lambda >= 0 ⊥ u_N = J_i x - c_i >= 0 and r_T = 0: our KKT system.
/// x0 is stored as the first initial guess (/guesses), x_ref and lambda_ref, when known, as the
/// solution (/solution: v = x_ref, r = (lambda_ref, 0, 0), u = J x_ref - c). The QP's metadata
/// goes to /fclib_global/info/description as JSON; per-row contact metadata is not exported.
///
/// Built only when CMake finds pkg-config `fclib`; otherwise every function throws InputError
/// saying so.
#include "problems/qpsnap.hpp"

#include <string>

namespace cb {

/// True for the names convert treats as FCLIB files (.hdf5, .h5).
bool is_fclib_path(const std::string& path);

/// Writes atomically (temporary name in the same folder, then rename).
void write_fclib_global(const std::string& path, const Qp& qp, const SnapshotExtras* extras = nullptr);

/// Reads an `fclib_global` problem written as above and validates it like a snapshot. Throws
/// InputError("PATH: FIELD: problem") for anything outside the mapping (equality constraints G,
/// spacedim != 3, mu != 0, tangential entries in H or w): friction is never dropped silently.
Qp read_fclib_global(const std::string& path, SnapshotExtras* extras = nullptr);

/// The FCLIB library version compiled against, or "" when not built.
std::string fclib_version();

}  // namespace cb
