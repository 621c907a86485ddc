#pragma once
/// The file format shared by the resume states of `simulate` (resume_state.*) and `chains`
/// (chains_state.*): a magic line, one line of JSON (identity, counters, vector sizes), then the
/// raw little-endian doubles of the vectors in the order the header lists them. Written
/// atomically (temporary, then rename); read back only when it is whole.
#include "solvers/core/types.hpp"

#include <nlohmann/json.hpp>

#include <optional>
#include <string>
#include <vector>

namespace cb::sim {

/// Writes MAGIC, the header and the vectors' doubles to PATH atomically.
void write_state_file(const std::string& path, const char* magic, const nlohmann::json& head,
                      const std::vector<const Vec*>& vectors);

struct StateFile {
    std::string path;
    nlohmann::json head;
    std::string body;  ///< the doubles after the header line

    /// The vectors of these sizes, in order; InputError unless the sizes are non-negative and
    /// cover the body exactly.
    std::vector<Vec> vectors(const std::vector<long>& sizes) const;
};

/// std::nullopt when nothing is at PATH; else the header and body, or InputError naming `what`
/// ("a resume state") when the magic or the header line is not this version's.
std::optional<StateFile> read_state_file(const std::string& path, const char* magic, const std::string& what);

}  // namespace cb::sim
