#pragma once
/// Reference solutions (x*, F*) of the ORIGINAL QP for the energy figure of docs/accuracy.md,
/// computed with the `active-set` solver (every row, tol 1e-10) and cached by snapshot content
/// hash and method (solver, settings, REFERENCE_VERSION): <cache_dir()>/reference/<key>-<method hash>.json.
#include "solvers/core/qp.hpp"

#include <nlohmann/json.hpp>
#include <string>

namespace cb {

/// Bump when the reference computation changes in a way its settings do not show (cached
/// references of another version are recomputed).
/// 3: the record holds solution_extent (the scene size of a problem without geometry).
constexpr int REFERENCE_VERSION = 3;

/// {"objective": F*, "objective_x0": F(x0), "solution_extent": extent of x* (null when unusable),
///  "source": "active-set", "status", "accuracy": {...}, "key", "cached": bool}. `key` is the
/// snapshot hash. Pass the QP in the file, never a decoupled one: F* is the original problem's
/// optimum for every solver. A failed reference solve is still cached, with its status, and
/// "objective" null.
nlohmann::json reference_solution(const Qp& qp, const std::string& key, const std::string& cache = "");

/// The cached reference of snapshot `key`, or null when none is cached (nothing is computed).
nlohmann::json cached_reference(const std::string& key, const std::string& cache = "");

/// Adds "reference" to a run record, "energy_gap" = |F - F*| / (d_ref l^2) (docs/accuracy.md; d_ref
/// and l from the record's stiffness_scale and length_scale) to it and as a history column
/// (null where undefined). Refuses (adds nothing but "reference") a reference whose key is not the
/// record's snapshot hash (a reduced QP's F* is not the original's).
void attach_reference(nlohmann::json& record, const nlohmann::json& reference);

}  // namespace cb
