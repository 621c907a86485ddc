#pragma once
/// FCLIB (HDF5) export and import of the contact QP.
/// Ref: FCLIB, fclib.h (the global problem  M v = H r + f,  u = H'v + w,  C*_mu ∋ u ⊥ r ∈ C_mu;
/// the local one  u = W r + q,  C*_mu ∋ u ⊥ r ∈ C_mu; each contact's u and r are (normal, tangents)).
///
/// Export of a frictional snapshot (qp.friction with mu): the same, with mu, H's tangent columns
/// 3i+1, 3i+2 = T's rows 2i, 2i+1 and w_T = -cT (the inverse of keep_friction below); h and v0
/// have no FCLIB field and are not written.
/// Export, as a frictionless `fclib_global` problem: v = x, M = A, f = b, spacedim 3, one contact
/// per row i of J with mu_i = 0; H is n x 3m with column 3i = row i of J (the normal) and columns
/// 3i+1, 3i+2 (the tangents) empty; w = (-c_i, 0, 0) per contact. With mu = 0 the cone condition
/// reads r_N = lambda >= 0 ⊥ u_N = J_i x - c_i >= 0 and r_T = 0: our KKT system. x0 is stored as
/// the first initial guess (/guesses), x_ref and lambda_ref, when known, as the solution. The QP's
/// metadata goes to /fclib_global/info/description as JSON; per-row contact metadata (kinds,
/// depths, vertices) is not exported, so a .qpsnap -> FCLIB -> .qpsnap trip keeps A, b, x0, J, c
/// and the references bit for bit but not the snapshot's bytes (nor its content hash).
///
/// Import, of files as real writers (Siconos, LMGC90, libfclib) write them: matrices as triplets
/// in CSparse's convention (p = column indices, i = row indices, nz entries; p, i and x may hold
/// nz or nzmax values), compressed columns (nz = -1) or rows (nz = -2); a symmetric matrix stored
/// as one triangle is mirrored; spacedim 2 or 3 (the normal is each contact's first component).
///   global: A = M, b = f, J = the normal columns of H (transposed), c = -w_N.
///   local:  A = W_NN, b = -q_N, J = I, c = 0 (the normal block's LCP u_N = W_NN r_N + q_N).
/// With mu = 0 on every contact this is exact (r_T = 0, so tangential entries carry no force).
/// Friction is dropped only when asked (options.drop_friction), and then recorded in the QP's
/// meta.provenance; a global problem's is kept with options.keep_friction (see there); the file's
/// /solution is kept only when the mapping is exact and frictionless.
///
/// Built only when CMake finds pkg-config `fclib`; otherwise every function throws InputError
/// saying so.
#include "problems/qpsnap.hpp"
#include "solvers/core/friction_global.hpp"
#include "solvers/core/friction_problem.hpp"

#include <string>

namespace cb {

/// True for the names convert writes as FCLIB files (.hdf5, .h5).
bool is_fclib_path(const std::string& path);

/// Writes atomically (temporary name in the same folder, then rename).
void write_fclib_global(const std::string& path, const Qp& qp, const SnapshotExtras* extras = nullptr);

struct FclibReadOptions {
    bool drop_friction = false;  ///< mu != 0 accepted: its normal part only (recorded in meta.provenance)
    /// mu != 0 in an fclib_global problem kept as the snapshot's friction (solvers/core/qp.hpp Friction):
    /// mu, T = the tangent columns of H (transposed: rows 2i, 2i+1 = columns 3i+1, 3i+2), cT = -w_T.
    /// Then u_i = (J_i x - c_i, T_i x - cT_i) = H_i' v + w_i exactly, and r = (lambda, lambda_T).
    /// The file's /solution is not kept (a snapshot's reference holds no tangential multipliers).
    /// drop_friction wins when both are set; a local problem's friction is never kept (no A).
    bool keep_friction = false;
    bool symmetrise = false;     ///< A not symmetric to rounding: (A + A')/2 (recorded) instead of refused
};

/// Reads an `fclib_global` or `fclib_local` problem (whichever the file holds) and validates it
/// like a snapshot. Throws InputError("PATH: FIELD: problem") naming the HDF5 dataset for anything
/// outside the mapping: equality constraints (G, V/R), mu != 0 without drop_friction, bad sizes,
/// indices, values, an asymmetric A, external links or external storage, n = 0.
Qp read_fclib(const std::string& path, SnapshotExtras* extras = nullptr, const FclibReadOptions& options = {});

/// read_fclib for a file that must hold an `fclib_global` problem.
Qp read_fclib_global(const std::string& path, SnapshotExtras* extras = nullptr, const FclibReadOptions& options = {});

/// Reads an `fclib_local` problem as the frictional problem it is (W, q, mu; friction kept), for
/// the frictional solvers (friction-solve). Same hostile-file rules as read_fclib: spacedim must
/// be 3, W square with 3 rows per contact, q of its size, every mu finite and >= 0, no V/R.
FrictionLocal read_fclib_local_friction(const std::string& path);

/// Reads an `fclib_global` problem as the frictional problem it is (M, H, f, w, mu; friction kept).
/// Same hostile-file rules: spacedim must be 3 (two tangents per contact), M square (one triangle
/// mirrored, otherwise symmetric to 1e-12 of its largest entry), H with M's rows and 3 columns per
/// contact, f, w and mu of those sizes, every mu finite and >= 0, no equality constraints (G).
FrictionGlobal read_fclib_global_friction(const std::string& path);

/// read_fclib_local_friction or read_fclib_global_friction, whichever the file holds: exactly one
/// of `local` and `global` is filled; returns "fclib_local" or "fclib_global".
std::string read_fclib_friction(const std::string& path, FrictionLocal& local, FrictionGlobal& global);

/// "fclib_global", "fclib_local" or "" for an HDF5 file holding neither (or when not built).
/// Opens no external file; throws InputError only when the file cannot be opened as HDF5.
std::string fclib_kind(const std::string& path);

/// A summary of an FCLIB file for `info` (kind, spacedim, contacts, unknowns, mu range, title,
/// whether a solution and guesses are present), without reading its matrices.
nlohmann::json describe_fclib(const std::string& path);

/// The FCLIB library version compiled against, or "" when not built.
std::string fclib_version();

}  // namespace cb
