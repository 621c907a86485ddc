#pragma once
/// Name -> factory for every solver. A new solver is one file pair and one line in
/// builtin_solvers.cpp.
#include "solvers/core/settings.hpp"
#include "solvers/core/solver.hpp"

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace cb {

using SolverFactory = std::function<std::unique_ptr<Solver>(const nlohmann::json& settings)>;

struct SolverEntry {
    SolverFactory make;
    std::string description;  ///< one line for `--help`
    /// solver-specific keys, after any common key whose default the solver changes (the common
    /// ones are implied: --help prints common_setting_docs() first)
    std::vector<SettingDoc> settings;
    std::string applies_to = "any J";  ///< which problems it accepts, for `contactbench solvers`
    std::string library;               ///< external peers: the library and its version ("Bullet 3.24"); else empty
    bool needs_settings = false;  ///< cannot run without its own settings (command: argv); left out of "every solver"
};

/// A solver's registry entry in one line: T built from its settings struct S (S::common plus the
/// rows of `table`, read strictly by read_settings: unknown keys and bad values name `name` and the
/// key), with `--help`'s description and setting docs (a common default that S's initial `common`
/// changes first, then the table's rows) and the applicability line.
///
///   SolverEntry cg_entry() { return solver_entry<CgSolver>("cg", cg_settings_table(), "...", "ignores J"); }
template <class T, class S>
SolverEntry solver_entry(const std::string& name, const SettingsTable<S>& table, std::string description,
                         std::string applies_to = "any J")
{
    SolverEntry entry;
    entry.make = [name, &table](const nlohmann::json& settings) -> std::unique_ptr<Solver> {
        return std::make_unique<T>(read_settings(settings, name, table));
    };
    entry.description = std::move(description);
    entry.settings = common_default_overrides(S{}.common);  // a common default this solver changes
    const std::vector<SettingDoc> own = table.docs();
    entry.settings.insert(entry.settings.end(), own.begin(), own.end());
    entry.applies_to = std::move(applies_to);
    return entry;
}

class SolverRegistry {
public:
    /// Throws std::logic_error on a duplicate name.
    void add(const std::string& name, SolverEntry entry);
    /// Throws InputError naming the known solvers when `name` is not registered, and the
    /// solver's InputError when a setting is bad.
    std::unique_ptr<Solver> create(const std::string& name, const nlohmann::json& settings) const;
    const SolverEntry& entry(const std::string& name) const;
    bool contains(const std::string& name) const { return m_entries.count(name) != 0; }
    std::vector<std::string> names() const;  ///< sorted

private:
    std::map<std::string, SolverEntry> m_entries;
};

/// Explicit registration (static self-registration would vanish from a static library).
void register_builtin_solvers(SolverRegistry& registry);
/// The registry with every built-in solver.
const SolverRegistry& builtin_registry();

/// Adds a registration that builtin_registry() runs after register_builtin_solvers: solvers
/// living above solvers/ (harness/command_solver writes files, which solvers/ never does) join
/// the one registry this way. Must be called before the first builtin_registry() call (main()
/// does it first thing); later, or twice with the same function, it throws std::logic_error.
void add_builtin_registration(void (*registration)(SolverRegistry&));

}  // namespace cb
