#pragma once
/// The state `contactbench chains` resumes from (the same command into a folder holding an
/// interrupted run of the same inputs): every chain's positions, velocities, power-method warm
/// start and step count, which chains stopped on a blow-up, and the two pictured frames chosen so
/// far, so that the resumed frames are bit for bit those of an uninterrupted run. Written as
/// OUT/chains.state after each complete frame (atomically: temporary, then rename); removed once
/// chains.json is written.
///
/// Format: "cb-chains-resume 1\n", one line of JSON (identity, counters, vector sizes), then the
/// raw little-endian doubles of each chain's x, v and eigenvector, then each pictured frame's
/// positions of every chain.
#include "solvers/core/types.hpp"

#include <nlohmann/json.hpp>

#include <optional>
#include <string>
#include <vector>

namespace cb::sim {

/// A frame kept for a picture: where a figure of the shown chain was largest so far, and every
/// chain's positions there (empty: none yet).
struct PicturedFrame {
    long frame = -1;
    double value = -1;
    std::vector<Vec> x;
};

struct ChainsState {
    nlohmann::json identity;  ///< the inputs: resuming with other inputs is refused
    long frames_done = 0;     ///< frames 0 .. frames_done-1 are whole in chains.csv
    long csv_bytes = 0;       ///< chains.csv's length then
    std::vector<long> steps_done;
    std::vector<bool> stopped;  ///< chains stopped by a blow-up
    std::vector<Vec> x, v, eigenvector;
    PicturedFrame difference, penetration;
};

/// OUT/chains.state
std::string chains_state_path(const std::string& out_dir);

void write_chains_state(const std::string& out_dir, const ChainsState& state);

/// The state in `out_dir`, or nothing when there is none; InputError naming the file when it is
/// there but unreadable or damaged.
std::optional<ChainsState> read_chains_state(const std::string& out_dir);

}  // namespace cb::sim
