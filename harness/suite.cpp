#include "harness/suite.hpp"

#include "harness/results.hpp"
#include "problems/qpsnap.hpp"
#include "problems/synthetic.hpp"
#include "solvers/core/types.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fnmatch.h>
#include <glob.h>
#include <map>
#include <set>

namespace cb {

namespace fs = std::filesystem;

namespace {

const std::set<std::string>& known_keys()
{
    static const std::set<std::string> keys = {
        "name",        "snapshots", "generate",       "solvers",       "tol",   "time_limit_s", "repeat",
        "history_max", "reference", "decouple",       "decouple_seed", "chain", "description",  "tiers",
        "comment",     "timed",     "allow_commands", "length_scale"};
    return keys;
}

bool safe_name(const std::string& s)
{
    if (s.empty() || s[0] == '.') return false;
    for (char ch : s)
        if (!(std::isalnum(static_cast<unsigned char>(ch)) || ch == '-' || ch == '_' || ch == '.' || ch == '+'))
            return false;
    return s.find("__") == std::string::npos;  // "__" separates snapshot id and label in file names
}

std::string type_name(const nlohmann::json& v) { return v.type_name(); }

constexpr double MAX_TIME_LIMIT_S = 1e6;

double get_number(const nlohmann::json& j, const std::string& key, const std::string& where, double fallback,
                  double min_exclusive)
{
    if (!j.contains(key)) return fallback;
    const auto& v = j[key];
    if (!v.is_number()) throw_input_error(where, "/" + key, "expected a number, got " + type_name(v));
    const double d = v.get<double>();
    if (!(d > min_exclusive)) {
        char bound[32];
        std::snprintf(bound, sizeof(bound), "%g", min_exclusive);
        throw_input_error(where, "/" + key, "must be > " + std::string(bound) + ", got " + v.dump());
    }
    return d;
}

long get_integer(const nlohmann::json& j, const std::string& key, const std::string& where, long fallback,
                 long min_inclusive)
{
    if (!j.contains(key)) return fallback;
    const auto& v = j[key];
    if (!v.is_number_integer()) throw_input_error(where, "/" + key, "expected an integer, got " + v.dump());
    if (v.is_number_unsigned() && v.get<std::uint64_t>() > std::uint64_t(LONG_MAX))  // would wrap negative
        throw_input_error(where, "/" + key, "too large: " + v.dump() + " > " + std::to_string(LONG_MAX));
    const long d = v.get<long>();
    if (d < min_inclusive)
        throw_input_error(where, "/" + key, "must be >= " + std::to_string(min_inclusive) + ", got " + v.dump());
    return d;
}

bool get_bool(const nlohmann::json& j, const std::string& key, const std::string& where, bool fallback)
{
    if (!j.contains(key)) return fallback;
    if (!j[key].is_boolean()) throw_input_error(where, "/" + key, "expected true or false, got " + j[key].dump());
    return j[key].get<bool>();
}

std::string get_string(const nlohmann::json& j, const std::string& key, const std::string& where,
                       const std::string& fallback)
{
    if (!j.contains(key)) return fallback;
    if (!j[key].is_string()) throw_input_error(where, "/" + key, "expected a string, got " + j[key].dump());
    return j[key].get<std::string>();
}

/// An optional array of non-empty strings (snapshot id globs).
std::vector<std::string> get_patterns(const nlohmann::json& j, const std::string& key, const std::string& where)
{
    std::vector<std::string> out;
    if (!j.contains(key)) return out;
    const auto& v = j[key];
    if (!v.is_array() || v.empty())
        throw_input_error(where, "/" + key, "expected a non-empty array of snapshot id globs, got " + v.dump());
    for (size_t i = 0; i < v.size(); ++i) {
        if (!v[i].is_string() || v[i].get<std::string>().empty())
            throw_input_error(where, "/" + key + "/" + std::to_string(i),
                              "expected a non-empty string (a snapshot id glob), got " + v[i].dump());
        out.push_back(v[i].get<std::string>());
    }
    return out;
}

bool matches_any(const std::vector<std::string>& patterns, const std::string& id)
{
    for (const std::string& p : patterns)
        if (fnmatch(p.c_str(), id.c_str(), 0) == 0) return true;
    return false;
}

}  // namespace

long most_threads(const Suite& suite)
{
    long threads = 1;
    for (const SuiteSolver& s : suite.solvers)
        if (s.settings.contains("threads") && s.settings["threads"].is_number_integer())
            threads = std::max(threads, s.settings["threads"].get<long>());
    return threads;
}

std::vector<std::string> drop_unbuilt_optional_solvers(Suite& suite, const std::vector<std::string>& registered)
{
    const std::set<std::string> built(registered.begin(), registered.end());
    std::vector<std::string> notices;
    std::vector<SuiteSolver> kept;
    for (SuiteSolver& sv : suite.solvers) {
        if (sv.optional && !built.count(sv.solver)) {
            notices.push_back("optional solver '" + sv.label + "' (" + sv.solver +
                              ") is not built into this contactbench; its runs are skipped");
            continue;
        }
        kept.push_back(std::move(sv));
    }
    suite.solvers = std::move(kept);
    return notices;
}

bool solver_applies(const SuiteSolver& solver, const std::string& id)
{
    if (!solver.problems.empty() && !matches_any(solver.problems, id)) return false;
    return !matches_any(solver.skip_problems, id);
}

std::string fnv1a_hex(const std::string& bytes)
{
    std::uint64_t h = 1469598103934665603ULL;
    for (unsigned char ch : bytes) {
        h ^= ch;
        h *= 1099511628211ULL;
    }
    char buffer[17];
    std::snprintf(buffer, sizeof(buffer), "%016llx", static_cast<unsigned long long>(h));
    return buffer;
}

std::string cache_dir()
{
    if (const char* c = std::getenv("CB_CACHE"); c && *c) return c;
    if (const char* home = std::getenv("HOME"); home && *home) return std::string(home) + "/.cache/contactbench";
    return "/tmp/contactbench-cache";
}

std::string paper_data_cache() { return cache_dir() + "/paper-data"; }

std::string paper_data_dir(bool given, const std::string& option)
{
    if (given) return option;
    return std::filesystem::is_directory(paper_data_cache()) ? paper_data_cache() : std::string();
}

Suite parse_suite(const nlohmann::json& j, const std::string& where)
{
    if (!j.is_object()) throw_input_error(where, "", "a suite must be a JSON object, got " + type_name(j));
    for (const auto& item : j.items())
        if (!known_keys().count(item.key())) {
            std::string known;
            for (const auto& k : known_keys()) known += (known.empty() ? "" : ", ") + k;
            throw_input_error(where, "/" + item.key(), "unknown key; known: " + known);
        }
    Suite s;
    s.path = where;
    s.raw = j;
    if (!j.contains("name")) throw_input_error(where, "/name", "missing (a file-name safe suite name)");
    s.name = get_string(j, "name", where, "");
    if (!safe_name(s.name))
        throw_input_error(where, "/name", "expected letters, digits, '-', '_', '.', '+', got '" + s.name + "'");
    if (j.contains("snapshots")) {
        const auto& v = j["snapshots"];
        if (!v.is_array())
            throw_input_error(where, "/snapshots", "expected an array of paths/globs, got " + type_name(v));
        for (size_t i = 0; i < v.size(); ++i) {
            if (v[i].is_object()) {  // a simulation folder with a frame selection
                s.simulations.push_back(parse_suite_simulation(v[i], where + ": /snapshots/" + std::to_string(i)));
                s.simulations.back().position = s.snapshots.size();
                s.simulations.back().field = "/snapshots/" + std::to_string(i);
                continue;
            }
            if (!v[i].is_string() || v[i].get<std::string>().empty())
                throw_input_error(where, "/snapshots/" + std::to_string(i),
                                  "expected a non-empty string, got " + v[i].dump());
            s.snapshots.push_back(v[i].get<std::string>());
        }
    }
    std::set<std::string> ids;
    if (j.contains("generate")) {
        const auto& v = j["generate"];
        if (!v.is_array()) throw_input_error(where, "/generate", "expected an array, got " + type_name(v));
        for (size_t i = 0; i < v.size(); ++i) {
            const std::string at = where + ": /generate/" + std::to_string(i);
            const auto& e = v[i];
            if (!e.is_object()) throw_input_error(at, "", "expected an object, got " + type_name(e));
            for (const auto& item : e.items())
                if (item.key() != "id" && item.key() != "family" && item.key() != "seed" && item.key() != "params")
                    throw_input_error(at, "/" + item.key(), "unknown key; known: family, id, params, seed");
            SuiteGenerate g;
            if (!e.contains("family")) throw_input_error(at, "/family", "missing");
            g.family = get_string(e, "family", at, "");
            g.seed = static_cast<std::uint64_t>(get_integer(e, "seed", at, 0, 0));
            if (e.contains("params")) {
                if (!e["params"].is_object())
                    throw_input_error(at, "/params", "expected an object, got " + type_name(e["params"]));
                g.params = e["params"];
            }
            g.id = get_string(e, "id", at, g.family + "-s" + std::to_string(g.seed));
            if (!safe_name(g.id))
                throw_input_error(at, "/id", "expected a file-name safe id without '__', got '" + g.id + "'");
            if (!ids.insert(g.id).second) throw_input_error(at, "/id", "duplicate id '" + g.id + "'");
            s.generate.push_back(std::move(g));
        }
    }
    if (s.snapshots.empty() && s.simulations.empty() && s.generate.empty())
        throw_input_error(where, "/snapshots", "the suite names no snapshots and generates none");
    if (!j.contains("solvers")) throw_input_error(where, "/solvers", "missing (an array of {label, solver, settings})");
    const auto& solvers = j["solvers"];
    if (!solvers.is_array() || solvers.empty())
        throw_input_error(where, "/solvers", "expected a non-empty array, got " + solvers.dump());
    std::set<std::string> labels;
    for (size_t i = 0; i < solvers.size(); ++i) {
        const std::string at = where + ": /solvers/" + std::to_string(i);
        const auto& e = solvers[i];
        SuiteSolver sv;
        if (e.is_string()) {
            sv.solver = sv.label = e.get<std::string>();
        } else if (e.is_object()) {
            static const std::set<std::string> solver_keys = {"label",    "solver",   "settings",
                                                              "optional", "problems", "skip_problems"};
            for (const auto& item : e.items())
                if (!solver_keys.count(item.key()))
                    throw_input_error(at, "/" + item.key(),
                                      "unknown key; known: label, optional, problems, settings, skip_problems, solver");
            if (!e.contains("solver")) throw_input_error(at, "/solver", "missing (a registered solver name)");
            sv.solver = get_string(e, "solver", at, "");
            sv.label = get_string(e, "label", at, sv.solver);
            if (e.contains("settings")) {
                if (!e["settings"].is_object())
                    throw_input_error(at, "/settings", "expected an object, got " + type_name(e["settings"]));
                sv.settings = e["settings"];
            }
            sv.optional = get_bool(e, "optional", at, false);
            sv.problems = get_patterns(e, "problems", at);
            sv.skip_problems = get_patterns(e, "skip_problems", at);
        } else {
            throw_input_error(at, "", "expected an object {label, solver, settings} or a name, got " + e.dump());
        }
        if (!safe_name(sv.label))
            throw_input_error(at, "/label", "expected a file-name safe label without '__', got '" + sv.label + "'");
        if (!labels.insert(sv.label).second) throw_input_error(at, "/label", "duplicate label '" + sv.label + "'");
        s.solvers.push_back(std::move(sv));
    }
    s.tol = get_number(j, "tol", where, s.tol, 0.0);
    s.time_limit_s = get_number(j, "time_limit_s", where, s.time_limit_s, -1.0);
    if (s.time_limit_s < 0)
        throw_input_error(where, "/time_limit_s", "must be >= 0 (0 disables), got " + j["time_limit_s"].dump());
    // The limit becomes a clock deadline (int64 nanoseconds overflow past 292 years, and 1e308
    // failed every run): more than a million seconds (11.6 days) is a typo, not a budget.
    if (s.time_limit_s > MAX_TIME_LIMIT_S)
        throw_input_error(where, "/time_limit_s",
                          "must be <= 1e6 seconds (11.6 days; 0 disables), got " + j["time_limit_s"].dump());
    s.repeat = static_cast<int>(get_integer(j, "repeat", where, 1, 1));
    if (s.repeat > 1000 || get_integer(j, "repeat", where, 1, 1) > 1000)  // no int wrap-around
        throw_input_error(where, "/repeat", "must be <= 1000, got " + j["repeat"].dump());
    s.history_max = get_integer(j, "history_max", where, s.history_max, 2);
    s.reference = get_bool(j, "reference", where, false);
    s.decouple = get_string(j, "decouple", where, "auto");
    static const std::set<std::string> orders = {"auto", "none", "authors", "random", "depth"};
    if (!orders.count(s.decouple))
        throw_input_error(where, "/decouple",
                          "expected one of auto, none, authors, random, depth, got '" + s.decouple + "'");
    s.decouple_seed = static_cast<std::uint64_t>(get_integer(j, "decouple_seed", where, 0, 0));
    s.chain = get_bool(j, "chain", where, false);
    s.length_scale = get_number(j, "length_scale", where, 0.0, 0.0);
    if (!std::isfinite(s.length_scale))
        throw_input_error(where, "/length_scale", "must be a finite number > 0, got " + j["length_scale"].dump());
    s.timed = get_bool(j, "timed", where, true);
    // Running a program named in a suite file is the suite author's explicit choice.
    s.allow_commands = get_bool(j, "allow_commands", where, false);
    for (size_t i = 0; i < s.solvers.size(); ++i)
        if (s.solvers[i].solver == "command" && !s.allow_commands)
            throw_input_error(
                where, "/solvers/" + std::to_string(i) + "/solver",
                "'command' runs an external program; the suite must opt in with \"allow_commands\": true");
    if (j.contains("tiers")) {
        const auto& t = j["tiers"];
        if (!t.is_array()) throw_input_error(where, "/tiers", "expected an array of numbers, got " + t.dump());
        for (const auto& x : t)
            if (!x.is_number()) throw_input_error(where, "/tiers", "expected an array of numbers, got " + t.dump());
    }
    return s;
}

Suite load_suite(const std::string& path) { return parse_suite(read_json_file(path), path); }

std::vector<SuiteSnapshot> resolve_snapshots(const Suite& suite, const std::string& generated_dir)
{
    const fs::path base = fs::path(suite.path).has_parent_path() ? fs::path(suite.path).parent_path() : fs::path(".");
    std::vector<std::pair<std::string, std::string>> found;  // (stem, path)
    std::set<std::string> seen_paths;
    auto add = [&](const fs::path& p) {
        std::error_code ec;  // a link loop has no canonical name: its run names the loop
        std::string key = fs::weakly_canonical(p, ec).string();
        if (ec) key = p.string();
        if (!seen_paths.insert(key).second) return;
        found.emplace_back(p.stem().string(), p.string());
    };
    // A FIFO, a device or a link loop named by the suite directly is refused by name (it once
    // read as "no such file").
    auto add_regular = [&](const fs::path& p, const std::string& field) {
        const std::string problem = regular_file_problem(p.string());
        if (!problem.empty()) throw_input_error(suite.path, field, "'" + p.string() + "': " + problem);
        add(p);
    };
    auto add_simulations_at = [&](size_t position) {
        for (const auto& sim : suite.simulations)
            if (sim.position == position)
                for (const auto& f : expand_suite_simulation(sim, suite.path)) add(f);
    };
    for (size_t i = 0; i <= suite.snapshots.size(); ++i) {
        add_simulations_at(i);
        if (i == suite.snapshots.size()) break;
        const std::string& pattern = suite.snapshots[i];
        const fs::path full = fs::path(pattern).is_absolute() ? fs::path(pattern) : base / pattern;
        const std::string field = "/snapshots/" + std::to_string(i);
        std::error_code ec;  // a link loop is no folder: named below as one
        if (fs::is_directory(full, ec)) {
            std::vector<fs::path> files;
            // As for a pattern, a FIFO or a link loop among them fails its own runs (by name).
            for (const auto& entry : fs::directory_iterator(full))
                if (entry.path().extension() == ".qpsnap" && !entry.is_directory(ec)) files.push_back(entry.path());
            std::sort(files.begin(), files.end());
            if (files.empty())
                throw_input_error(suite.path, field, "folder '" + full.string() + "' holds no .qpsnap file");
            for (const auto& f : files) add(f);
        } else if (pattern.find_first_of("*?[") != std::string::npos) {
            glob_t g{};
            const int rc = ::glob(full.c_str(), 0, nullptr, &g);
            std::vector<std::string> matches;
            if (rc == 0)
                for (size_t k = 0; k < g.gl_pathc; ++k) matches.push_back(g.gl_pathv[k]);
            ::globfree(&g);
            std::sort(matches.begin(), matches.end());
            if (matches.empty())
                throw_input_error(suite.path, field, "pattern '" + full.string() + "' matches no file");
            for (const auto& m : matches) add(m);
        } else {
            if (regular_file_problem(full.string()) == "not found")
                throw_input_error(suite.path, field, "no such file '" + full.string() + "'");
            add_regular(full, field);
        }
    }
    std::vector<SuiteSnapshot> out;
    std::map<std::string, int> uses;
    std::set<std::string> taken;
    for (const auto& g : suite.generate) taken.insert(g.id);
    for (const auto& [stem, path] : found) {
        std::string id = stem;
        // Snapshot ids must be unique: the second "frame-0001" becomes "frame-0001-2".
        while (taken.count(id)) id = stem + "-" + std::to_string(++uses[stem] + 1);
        taken.insert(id);
        out.push_back({id, path, false});
    }
    const std::string dir = generated_dir.empty() ? cache_dir() + "/generated" : generated_dir;
    for (const auto& g : suite.generate) {
        const nlohmann::json key = {{"family", g.family}, {"seed", g.seed}, {"params", g.params}, {"format", 1}};
        const std::string path = dir + "/" + g.family + "-" + fnv1a_hex(key.dump()) + ".qpsnap";
        if (!fs::is_regular_file(path)) {
            Qp qp;
            try {
                qp = make_synthetic(g.family, g.params, g.seed);
            } catch (const InputError& e) {
                throw_input_error(suite.path, "/generate (id " + g.id + ")", e.what());
            }
            fs::create_directories(dir);
            write_qpsnap(path, qp);
        }
        out.push_back({g.id, path, true});
    }
    return out;
}

}  // namespace cb
