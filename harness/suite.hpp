#pragma once
/// Suite files (INTERFACES.md "Suite JSON"): parse and validate strictly, expand snapshot
/// globs/folders, and generate synthetic snapshots into a cache keyed by their content.
#include <nlohmann/json.hpp>
#include <cstdint>
#include <string>
#include <vector>

namespace cb {

struct SuiteSolver {
    std::string label;   ///< unique in the suite, file-name safe; defaults to `solver`
    std::string solver;  ///< registry name (an unknown one is reported per run, not here)
    nlohmann::json settings = nlohmann::json::object();
    bool optional = false;  ///< a solver this build may lack (a peer): skipped with a notice when not registered
    std::vector<std::string> problems;       ///< glob patterns over snapshot ids it runs on (empty: all)
    std::vector<std::string> skip_problems;  ///< glob patterns over snapshot ids it leaves out
};

struct SuiteGenerate {
    std::string id;
    std::string family;
    std::uint64_t seed = 0;
    nlohmann::json params = nlohmann::json::object();
};

/// A `snapshots` entry that picks the snapshots of a simulation folder (`contactbench simulate
/// --out DIR`) from its steps.csv: {"sim": DIR, "frames": "a:b", "stride": k, "min_rows": r,
/// "newton": i, "scene": SCENE.json}. Frames a..b-1 (either end may be omitted; "a" is one frame),
/// every k-th of them, steps with at least r contact rows, Newton iteration i (default: all).
struct SuiteSimulation {
    size_t position = 0;  ///< number of string patterns listed before it (keeps the suite's order)
    std::string field;    ///< "/snapshots/<i>", for messages
    std::string folder;   ///< as written (relative to the suite file)
    long first = 0;       ///< first frame
    long end = -1;        ///< one past the last frame; -1: to the end
    long stride = 1;
    long min_rows = 0;
    long newton = -1;   ///< -1: every Newton iteration
    std::string scene;  ///< optional: the scene file, so that errors print the exact command
};

struct Suite {
    std::string path;  ///< the suite file
    std::string name;
    std::vector<std::string> snapshots;        ///< patterns, as written (relative to the suite file)
    std::vector<SuiteSimulation> simulations;  ///< simulation entries of `snapshots`
    std::vector<SuiteGenerate> generate;
    std::vector<SuiteSolver> solvers;
    double tol = 1e-6;           ///< default `tol` of every solver (a solver's own setting wins)
    double time_limit_s = 60.0;  ///< default `time_limit_s` of every solver (0 disables)
    int repeat = 1;
    long history_max = 2000;
    bool reference = false;
    std::string decouple = "auto";
    std::uint64_t decouple_seed = 0;
    bool chain = false;
    double length_scale = 0.0;  ///< > 0: the scene size l of every snapshot (docs/accuracy.md); 0: each its own
    std::string length_scale_source = "suite";  ///< "suite", or "given" when `run --length-scale` set it
    bool timed = true;            ///< false: times are not judged (counters only); `run --jobs` runs it in parallel
    bool allow_commands = false;  ///< true: `command` solvers (external programs) may run; without it they are refused
    nlohmann::json raw;           ///< the file as read
};

/// Reads and validates a suite file; InputError("SUITE: /field: problem") on any bad or unknown key.
Suite load_suite(const std::string& path);
/// Same from JSON already in memory (`where` names it in messages; relative paths resolve
/// against `base_dir`).
Suite parse_suite(const nlohmann::json& j, const std::string& where);

/// The most threads any label of the suite asks for (the common setting `threads`), 1 when none does.
long most_threads(const Suite& suite);

/// Removes the `optional` solver entries whose solver is not in `registered` (this build's
/// registry) and returns one notice per removed entry, naming its label and solver.
std::vector<std::string> drop_unbuilt_optional_solvers(Suite& suite, const std::vector<std::string>& registered);

/// Whether the entry runs on the snapshot `id`: it matches one of `problems` (when given) and
/// none of `skip_problems` (fnmatch globs). A job that does not apply is not a job of the suite.
bool solver_applies(const SuiteSolver& solver, const std::string& id);

/// One snapshot of a suite, resolved to a file.
struct SuiteSnapshot {
    std::string id;  ///< file stem (duplicates get "-2", "-3" ...) or the generate entry's id
    std::string path;
    bool generated = false;
};

/// The cache folder: $CB_CACHE, else $HOME/.cache/contactbench, else /tmp/contactbench-cache.
std::string cache_dir();
/// Where `make paper-data` writes the authors' data: cache_dir()/paper-data.
std::string paper_data_cache();
/// The authors' data folder of simulate and chains: `--data` when given, else paper_data_cache()
/// when it exists, else "" (a scene's "data:" meshes then use their stand-ins).
std::string paper_data_dir(bool given, const std::string& option);

/// Expands patterns (files, folders: every *.qpsnap inside, globs: sorted matches) in the
/// order listed, then the generate entries (written with write_qpsnap into
/// `generated_dir` (default cache_dir()/generated) under a name derived from a hash of
/// {family, seed, params}, reused when already there). A pattern matching nothing is an InputError.
std::vector<SuiteSnapshot> resolve_snapshots(const Suite& suite, const std::string& generated_dir = "");

/// Parses a simulation entry of `snapshots` (`at` names it in messages); InputError on bad keys.
SuiteSimulation parse_suite_simulation(const nlohmann::json& entry, const std::string& at);

/// The snapshot files a simulation entry selects, in frame order. InputError naming the suite
/// field when the folder, its steps.csv, a frame or a snapshot is missing, with the
/// `contactbench simulate` command that writes it.
std::vector<std::string> expand_suite_simulation(const SuiteSimulation& sim, const std::string& suite_path);

/// 64-bit FNV-1a as 16 hex digits.
std::string fnv1a_hex(const std::string& bytes);

}  // namespace cb
