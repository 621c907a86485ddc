#pragma once
/// The CI suite's problems (the generate block of suites/ci.json): plane-small, box and stiff have
/// bound rows (an axis plane, signed unit rows), plane-tilted and coupled do not.
#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace cb::test {

struct CiCase {
    std::string id, family;
    std::uint64_t seed;
    nlohmann::json params;
};

inline std::vector<CiCase> ci_cases()
{
    return {{"plane-small", "plane", 11, {{"nx", 4}, {"ny", 4}, {"nz", 4}}},
            {"plane-tilted", "plane", 12, {{"nx", 4}, {"ny", 3}, {"nz", 4}, {"tilt_deg", 20}}},
            {"coupled", "coupled", 13, {{"nx", 4}, {"ny", 2}, {"nz", 4}}},
            {"box", "box", 14, {{"nx", 4}, {"ny", 4}, {"nz", 4}}},
            {"stiff", "plane", 15, {{"nx", 4}, {"ny", 4}, {"nz", 4}, {"youngs", 1e9}}}};
}

}  // namespace cb::test
