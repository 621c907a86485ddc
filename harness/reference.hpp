#pragma once
/// Reference solutions (F*) for the relative objective error of DESIGN.md "Metrics", computed
/// with the `active-set` solver and cached by snapshot content hash and method (solver, settings,
/// kReferenceVersion): <cache_dir()>/reference/<key>-<method hash>.json.
#include "solvers/qp.hpp"

#include <nlohmann/json.hpp>
#include <string>

namespace cb {

/// Bump when the reference computation changes in a way its settings do not show (cached
/// references of another version are recomputed).
constexpr int kReferenceVersion = 1;

/// {"objective": F*, "objective_x0": F(x0), "source": "active-set", "status", "kkt": {...},
///  "kkt_rel", "key", "cached": bool}. `key` is the snapshot hash (plus a decoupling suffix when
/// the solvers saw a decoupled QP). A failed reference solve is still cached, with its status,
/// and "objective" null.
nlohmann::json reference_solution(const Qp& qp, const std::string& key, const std::string& cache = "");

/// Adds "reference" to a run record and the column "obj_rel" = |F - F*| / |F(x0) - F*| to its
/// history (null where undefined).
void attach_reference(nlohmann::json& record, const nlohmann::json& reference);

} // namespace cb
