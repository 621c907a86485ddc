#pragma once
/// Solver settings: the block every solver accepts, and a strict JSON reader that names the
/// offending field ("mprgp: /gamma: must be > 0, got -1") and rejects unknown keys.
#include "solvers/core/types.hpp"
#include "solvers/linalg/a_format.hpp"

#include <nlohmann/json.hpp>
#include <climits>
#include <functional>
#include <set>
#include <string>
#include <vector>

namespace cb {

/// Which measure `tol` bounds. Only SolveLoop (solvers/core/solve_loop.hpp) reads it.
enum class StopRule {
    ACCURACY,  ///< the common accuracy error e of docs/accuracy.md (default; the setting's name `kkt` is kept)
    NATIVE,    ///< the solver's published criterion; `tol` is then the paper's absolute tolerance
};
/// The setting's text: "kkt" or "native".
inline const char* to_string(StopRule rule) { return rule == StopRule::NATIVE ? "native" : "kkt"; }

/// Largest accepted max_iterations: counters stay far from overflow (a larger value is an error
/// naming the key, not a silent clamp).
constexpr long MAX_ITERATIONS_LIMIT = 1000000000000L;
/// Largest accepted `threads` (a larger value is an error naming the key).
constexpr long MAX_THREADS = 1024;

/// The default `tol`: the accuracy error e of a converged run (a millionth of the scene size).
/// The harness's verdict on a stop=native run uses it too (harness/runner.hpp).
constexpr double DEFAULT_TOL = 1e-6;

/// Settings every solver accepts; their keys, bounds and docs are one table
/// (common_settings_table() in settings.cpp), the defaults the initial values below.
struct CommonSettings {
    double tol =
        DEFAULT_TOL;  ///< on the accuracy error e (a fraction of the scene size), or the native residual (stop=native)
    StopRule stop = StopRule::ACCURACY;
    long max_iterations = 10000;       ///< outer iterations
    double time_limit_s = 0.0;         ///< 0 disables the limit
    std::uint64_t seed = 0;            ///< every random choice is seeded
    long threads = 1;                  ///< threads of the A-products (solvers/linalg/a_product.hpp); 1 = one core
    AFormat a_format = AFormat::AUTO;  ///< storage of A for the A-products (AOperator::prepare)

    /// stop=native. For a peer that passes `tol` to its library as that library's own tolerance;
    /// whether a solve converged is SolveLoop's decision, never the solver's.
    bool stops_on_native() const { return stop == StopRule::NATIVE; }
    /// These settings with another tol: a solver's own default, as its settings struct's initial
    /// `common` (active-set: `CommonSettings common = CommonSettings{}.with_tol(1e-10);`).
    CommonSettings with_tol(double value) const
    {
        CommonSettings copy = *this;
        copy.tol = value;
        return copy;
    }

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

    /// Reads the common block (tol, stop, max_iterations, time_limit_s, seed, threads, a_format); a key not given
    /// keeps its value in `defaults` (a solver's own defaults: active-set's tol is 1e-10).
    CommonSettings common(CommonSettings defaults = CommonSettings{});

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

/// A default value as `--help` prints it ("1e-6", "10000", "jacobi", "true").
std::string setting_default_text(double value);
inline std::string setting_default_text(long value) { return std::to_string(value); }
inline std::string setting_default_text(bool value) { return value ? "true" : "false"; }
inline std::string setting_default_text(const std::string& value) { return value; }

/// A solver's own settings, each declared once: key, field, bounds or choices, doc. The default
/// is the field's initial value in the settings struct S. The reader (read), the record (write)
/// and `--help` (docs) all come from the table, so they cannot drift apart.
///
///   static const SettingsTable<MySettings> table = SettingsTable<MySettings>()
///       .number("gamma", &MySettings::gamma, 0.0, 1e300, "proportioning constant")
///       .choice("precond", &MySettings::precond, {"none", "jacobi"}, "none | jacobi: ...");
///
/// Rows are read in order, so a row's default may depend on rows above it (`default_of`).
template <class S> class SettingsTable {
public:
    SettingsTable& number(const std::string& key, double S::*field, double min_exclusive, double max_inclusive,
                          const std::string& doc, std::function<double(const S&)> default_of = nullptr)
    {
        Row row{{key, setting_default_text(S{}.*field), doc}, {}, nullptr, nullptr, shown(field)};
        row.read = [=](SettingsReader& reader, S& s) {
            s.*field = reader.number(key, default_of ? default_of(s) : s.*field, min_exclusive, max_inclusive);
        };
        row.write = [=](const S& s, nlohmann::json& j) { j[key] = s.*field; };
        m_rows.push_back(std::move(row));
        return *this;
    }
    SettingsTable& integer(const std::string& key, long S::*field, long min_inclusive, long max_inclusive,
                           const std::string& doc)
    {
        Row row{{key, setting_default_text(S{}.*field), doc}, {}, nullptr, nullptr, shown(field)};
        row.read = [=](SettingsReader& reader, S& s) {
            s.*field = reader.integer(key, s.*field, min_inclusive, max_inclusive);
        };
        row.write = [=](const S& s, nlohmann::json& j) { j[key] = s.*field; };
        m_rows.push_back(std::move(row));
        return *this;
    }
    SettingsTable& boolean(const std::string& key, bool S::*field, const std::string& doc)
    {
        Row row{{key, setting_default_text(S{}.*field), doc}, {}, nullptr, nullptr, shown(field)};
        row.read = [=](SettingsReader& reader, S& s) { s.*field = reader.boolean(key, s.*field); };
        row.write = [=](const S& s, nlohmann::json& j) { j[key] = s.*field; };
        m_rows.push_back(std::move(row));
        return *this;
    }
    /// A string that must be one of `choices` (the reader's error lists them).
    SettingsTable& choice(const std::string& key, std::string S::*field, const std::vector<std::string>& choices,
                          const std::string& doc, std::function<std::string(const S&)> default_of = nullptr)
    {
        Row row{{key, setting_default_text(S{}.*field), doc}, choices, nullptr, nullptr, shown(field)};
        row.read = [=](SettingsReader& reader, S& s) {
            s.*field = reader.choice(key, default_of ? default_of(s) : s.*field, choices);
        };
        row.write = [=](const S& s, nlohmann::json& j) { j[key] = s.*field; };
        m_rows.push_back(std::move(row));
        return *this;
    }

    /// A row of another type (an enum, an unsigned seed): its own reader, writer and default text.
    SettingsTable& row(const std::string& key, std::function<std::string(const S&)> default_text,
                       const std::string& doc, std::function<void(SettingsReader&, S&)> read,
                       std::function<void(const S&, nlohmann::json&)> write,
                       const std::vector<std::string>& choices = {})
    {
        m_rows.push_back(
            Row{{key, default_text(S{}), doc}, choices, std::move(read), std::move(write), std::move(default_text)});
        return *this;
    }

    /// Reads every row (after reader.common(); the caller calls reader.finish()).
    void read(SettingsReader& reader, S& s) const
    {
        for (const Row& row : m_rows) row.read(reader, s);
    }
    /// Writes every row's effective value into `j` (beside common.to_json()).
    void write(const S& s, nlohmann::json& j) const
    {
        for (const Row& row : m_rows) row.write(s, j);
    }
    /// The `--help` lines, defaults from S{}.
    std::vector<SettingDoc> docs() const
    {
        std::vector<SettingDoc> out;
        for (const Row& row : m_rows) out.push_back(row.doc);
        return out;
    }
    /// The `--help` lines with the defaults taken from `defaults` instead of S{}.
    std::vector<SettingDoc> docs(const S& defaults) const
    {
        std::vector<SettingDoc> out;
        for (const Row& row : m_rows) {
            out.push_back(row.doc);
            out.back().default_value = row.default_text(defaults);
        }
        return out;
    }
    /// The allowed values of a choice row (empty for other rows or unknown keys).
    std::vector<std::string> choices(const std::string& key) const
    {
        for (const Row& row : m_rows)
            if (row.doc.key == key) return row.choices;
        return {};
    }

private:
    struct Row {
        SettingDoc doc;
        std::vector<std::string> choices;
        std::function<void(SettingsReader&, S&)> read;
        std::function<void(const S&, nlohmann::json&)> write;
        std::function<std::string(const S&)> default_text;  ///< the row's value as `--help` shows it
    };
    template <class T> static std::function<std::string(const S&)> shown(T S::*field)
    {
        return [field](const S& s) { return setting_default_text(s.*field); };
    }
    std::vector<Row> m_rows;
};

/// The common block as one table: key, type and bounds, default (CommonSettings{}), doc. The
/// reader (SettingsReader::common), the record (CommonSettings::to_json) and `--help`
/// (common_setting_docs) all read it.
const SettingsTable<CommonSettings>& common_settings_table();
/// `--help` lines for the common keys whose default `defaults` changes, e.g. active-set's
/// `CommonSettings common{...}` with tol 1e-10: "tol [1e-10] (this solver's default; the common one
/// is 1e-6)". Empty when a solver keeps every common default. They follow the common lines, so the
/// last line of a key is its default.
std::vector<SettingDoc> common_default_overrides(const CommonSettings& defaults);

/// A solver's whole settings struct S (a `common` block plus its own rows) from JSON: the common
/// table, then `table`, then unknown keys rejected; errors name `solver` and the key. Defaults are
/// the initial values of S, its common block included (a solver may start it from other values).
template <class S>
S read_settings(const nlohmann::json& settings, const std::string& solver, const SettingsTable<S>& table)
{
    SettingsReader reader(settings, solver);
    S s;
    s.common = reader.common(s.common);
    table.read(reader, s);
    reader.finish();
    return s;
}
/// The effective values of S as recorded in every results file: the common block and `table`'s rows.
template <class S> nlohmann::json write_settings(const S& s, const SettingsTable<S>& table)
{
    nlohmann::json j = s.common.to_json();
    table.write(s, j);
    return j;
}

}  // namespace cb
