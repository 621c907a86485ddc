#pragma once
/// A results folder judged whole before anything reads it as a result (compare, merge; the
/// Python loader applies the same rules, plots/loader.py). A folder `contactbench run` is
/// writing, or that a killed run left, or that holds a record not of its jobs, would otherwise
/// be read as if it were a finished run: a stale copy could hide a regression.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace cb {

/// Throws InputError("DIR: being written by `contactbench run` (pid N) ...") when another
/// process holds DIR/.lock; nothing is created.
void require_unlocked(const std::string& dir);

/// The run records of a finished results folder, sorted by file name, each with "_file". Refused
/// (InputError naming the file and the field) unless:
///  - no process holds DIR/.lock and DIR/suite.pending.json is absent (a run still going, or
///    killed: "incomplete");
///  - when DIR/jobs.json exists (every `run` writes it last): it lists exactly the run files
///    present, and says complete;
///  - every entry of DIR/runs/*.json is a regular file (a FIFO, device or link loop is named)
///    holding a JSON object; in a folder of `run` (with jobs.json) its name is
///    run_file_name(snapshot.id, label) (one record per job, never a copy of another job's
///    record) and "final" is not false (a run to be retried); in a bare folder of run files (by
///    hand, `stress --out`) no two records share (snapshot.id, label).
std::vector<nlohmann::json> read_finished_runs(const std::string& dir);

/// The checks of one run record against its file name (used by merge on each shard's files).
void check_run_record(const nlohmann::json& record, const std::string& path, const std::string& file_name);

}  // namespace cb
