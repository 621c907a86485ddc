#pragma once
/// Solver settings: the block every solver accepts, and a strict JSON reader that names the
/// offending field ("mprgp: /gamma: must be > 0, got -1") and rejects unknown keys.
#include "solvers/types.hpp"

#include <nlohmann/json.hpp>
#include <functional>
#include <set>
#include <string>
#include <vector>

namespace cb {

enum class StopRule {
    KKT,     ///< the common accuracy error e of docs/accuracy.md (default; the name `kkt` is kept)
    NATIVE,  ///< the solver's published criterion; `tol` is then the paper's absolute tolerance
};

/// Largest accepted max_iterations: counters stay far from overflow (a larger value is an error
/// naming the key, not a silent clamp).
constexpr long kMaxIterationsLimit = 1000000000000L;

/// Settings every solver accepts.
struct CommonSettings {
    double tol =
        1e-6;  ///< on the accuracy error e (a fraction of the scene size), or the native residual (stop=native)
    StopRule stop = StopRule::KKT;
    long max_iterations = 10000;  ///< outer iterations
    double time_limit_s = 0.0;    ///< 0 disables the limit
    std::uint64_t seed = 0;       ///< every random choice is seeded

    nlohmann::json to_json() const;
};

/// Help line for one setting (for `contactbench solve --solver NAME --help`).
struct SettingDoc {
    std::string key;
    std::string default_value;
    std::string doc;
};

/// Reads keys from a settings object, checks them, and remembers which were read so that
/// finish() can reject unknown keys. Every error is an InputError naming solver and key.
class SettingsReader {
public:
    SettingsReader(const nlohmann::json& settings, std::string where);

    /// Reads the common block (tol, stop, max_iterations, time_limit_s, seed).
    CommonSettings common();

    double number(const std::string& key, double fallback, double min_exclusive = -1e300, double max_inclusive = 1e300);
    long integer(const std::string& key, long fallback, long min_inclusive = LONG_MIN, long max_inclusive = LONG_MAX);
    bool boolean(const std::string& key, bool fallback);
    /// A string that must be one of `allowed`.
    std::string choice(const std::string& key, const std::string& fallback, const std::vector<std::string>& allowed);
    /// Throws on any key that no accessor asked for.
    void finish() const;

private:
    const nlohmann::json* find(const std::string& key);
    [[noreturn]] void fail(const std::string& key, const std::string& problem) const;

    nlohmann::json m_settings;
    std::string m_where;
    std::set<std::string> m_read;
};

/// Common settings' help lines (each solver appends its own).
std::vector<SettingDoc> common_setting_docs();

/// Converts "key=value" strings (command line --set) to JSON: numbers, true/false, else string.
nlohmann::json parse_set_arguments(const std::vector<std::string>& assignments);

}  // namespace cb
