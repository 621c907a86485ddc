#pragma once
/// The stress families of `contactbench stress` (DESIGN.md "Check numerical stability"): small
/// seeded QPs (a few hundred to a few thousand DOF) at several severities, built on
/// make_synthetic where possible: stiffness, extreme units, tiny and huge time steps, badly
/// scaled rows, degenerate J (duplicated, parallel, zero rows, many rows on one vertex),
/// infeasible sets, empty J, nearly singular A, m close to n, ill-conditioned random SPD; and
/// "fem-sim": QPs of our own simulator (sim/) on stiff and fast variants of the demo scene.
#include "solvers/core/qp.hpp"

#include <nlohmann/json.hpp>
#include <cstdint>
#include <string>
#include <vector>

namespace cb {

struct StressCase {
    std::string id;         ///< unique, e.g. "stiffness-1e12"
    std::string family;     ///< stress family, e.g. "stiffness" (several cases share one)
    int severity = 0;       ///< 0 = baseline, 1 mild, 2 hard, 3 extreme
    std::string synthetic;  ///< make_synthetic family the case starts from, or "fem-sim": a snapshot
                            ///< of our simulator on the demo scene (params: youngs, speed, h, frames)
    nlohmann::json params = nlohmann::json::object();  ///< its params
    std::string
        modifier;  ///< "" or a transform applied after generation ("parallel-rows", "one-vertex", "translate-100m")
    std::uint64_t seed = 1;
    std::string description;  ///< one line
};

/// Every stress case, in a fixed order. `quick`: the 4-case subset used by tests and CI.
std::vector<StressCase> stress_cases(bool quick = false);

/// Cases whose id or family is in `names` (each name must match at least one case, else
/// InputError naming it and the known ids).
std::vector<StressCase> select_stress_cases(const std::vector<StressCase>& all, const std::vector<std::string>& names);

/// Generates the QP of a case (deterministic). Throws InputError on a bad case.
Qp make_stress_qp(const StressCase& stress_case);

}  // namespace cb
