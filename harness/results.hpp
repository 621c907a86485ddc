#pragma once
/// The results folder (INTERFACES.md "Results folder"): atomic file writes, per-run JSON files
/// DIR/runs/<snapshot-id>__<label>.json and DIR/summary.csv built from them.
#include "problems/io_util.hpp"  // write_file_atomic

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace cb {

/// JSON, indented by 1, NaN/Inf as null, written atomically.
void write_json_atomic(const std::string& path, const nlohmann::json& value);
/// Reads a JSON file; throws InputError("PATH: ...") when it is missing, not a regular file,
/// nested deeper than MAX_JSON_DEPTH or not JSON.
nlohmann::json read_json_file(const std::string& path);

/// File name of a run: "<snapshot-id>__<label>.json".
std::string run_file_name(const std::string& snapshot_id, const std::string& label);

/// Every DIR/runs/*.json, sorted by file name (unparsable files throw InputError).
std::vector<nlohmann::json> read_runs(const std::string& dir);

/// The summary.csv columns, in order.
const std::vector<std::string>& summary_columns();
/// One CSV line (no newline) for a run record.
std::string summary_row(const nlohmann::json& run, const std::string& suite_name);
/// The whole CSV text (header + one row per run, in the order given).
std::string summary_csv(const std::vector<nlohmann::json>& runs, const std::string& suite_name);
/// Rewrites DIR/summary.csv from DIR/runs/*.json (atomic). Returns the number of runs.
size_t write_summary(const std::string& dir, const std::string& suite_name);

}  // namespace cb
