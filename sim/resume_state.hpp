#pragma once
/// The state a simulation resumes from (`contactbench simulate` into a folder holding an
/// interrupted run of the same inputs): everything a frame's steps read besides the scene, so
/// that the resumed frames are bit for bit those of an uninterrupted run. Written as
/// OUT/resume.state after each complete frame (atomically: temporary, then rename).
///
/// Format: "cb-resume 1\n", one line of JSON (identity, counters, vector sizes), then the raw
/// little-endian doubles of x, v, the power method's eigenvector and the strip frames' positions.
#include "solvers/core/types.hpp"

#include <nlohmann/json.hpp>

#include <optional>
#include <string>
#include <vector>

namespace cb::sim {

struct ResumeState {
    nlohmann::json identity;         ///< the inputs: resuming with other inputs is refused
    long frames_done = 0;            ///< frames 0 .. frames_done-1 are whole in the tables
    long steps_done = 0;             ///< time steps taken (the random decoupling order's seed offset)
    bool finished = false;           ///< the run ended (all frames, or a blow-up): simulation.json written
    bool blow_up = false;            ///< it ended in a blow-up
    bool peak_reset = true;          ///< the kernel accepted the stage peak resets so far
    Vec x, v, eigenvector;           ///< positions, velocities, the power method's warm start
    std::vector<long> strip_frames;  ///< frames pictured so far, and their positions
    std::vector<Vec> strip_x;
};

/// OUT/resume.state
std::string resume_state_path(const std::string& out_dir);

void write_resume_state(const std::string& out_dir, const ResumeState& state);

/// The state in `out_dir`, or nothing when there is none; InputError naming the file when it
/// is there but unreadable or damaged.
std::optional<ResumeState> read_resume_state(const std::string& out_dir);

}  // namespace cb::sim
