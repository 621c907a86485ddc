#pragma once
/// `command`: a solver in any language, run as an external program (docs/INTERFACES.md "The
/// command protocol"). The harness writes the QP it gives the solver as a .qpsnap and the
/// settings as JSON into a fresh work folder, runs argv (no shell; {snapshot}, {settings} and
/// {out} replaced by paths), kills the program at time_limit_s, and reads back from {out}:
/// x.{npy,mtx,txt} (required), lambda.{npy,mtx,txt}, lambda_t.{npy,mtx,txt} (a frictional
/// snapshot's 2m tangential multipliers) and result.json (status, iterations,
/// self-reported times, residual, history with optional iterates). The run is then judged like
/// any registry solver's: on the ORIGINAL QP, so a wrong x claimed `converged` is `unconfirmed`.
///
/// Statuses: killed at the limit -> time_limit; crashed (signal, non-zero exit, not startable)
/// -> diverged with info.command.crashed; unusable output (no x, wrong length, NaN, bad
/// result.json) -> diverged with info.command.garbage. Lives in harness/ because it writes
/// files (solvers/ never does); main() adds it to the registry (install_command_solver).
#include "solvers/core/registry.hpp"
#include "solvers/core/settings.hpp"
#include "solvers/core/solver.hpp"

#include <string>
#include <utility>
#include <vector>

namespace cb {

struct CommandSettings {
    CommonSettings common;
    std::vector<std::string> argv;  ///< the program and its arguments, placeholders replaced at run time
    std::string accepts = "any";    ///< any | decoupled (the harness decouples a coupled J first)
    std::string time = "harness";   ///< harness | self: which time is the run's solve_s
    bool keep_files = false;        ///< keep the work folder (its path goes to info.command.workdir)

    static CommandSettings from_json(const nlohmann::json& settings);
    nlohmann::json to_json() const;
};

/// The time limit of a command solver whose time_limit_s is 0 (none): 600 s. A registry solver
/// without a limit ends by its iteration cap; an external program may never end, and a suite of
/// them must not wait forever on one. Ten minutes is long for one QP solve and short enough that
/// a hang is noticed; set time_limit_s for longer runs.
inline constexpr double DEFAULT_COMMAND_TIME_LIMIT_S = 600.0;

/// argv's placeholders ("{snapshot}", ...) replaced by their values in one left-to-right pass:
/// a value is never scanned again, so a path holding "{out}" stays as it is.
std::string expand_placeholders(const std::string& arg, const std::vector<std::pair<std::string, std::string>>& values);

/// The protocol version written into settings.json.
inline constexpr int COMMAND_PROTOCOL_VERSION = 1;

class CommandSolver : public Solver {
public:
    explicit CommandSolver(CommandSettings settings) : m_settings(std::move(settings)) {}
    std::string name() const override { return "command"; }
    nlohmann::json settings() const override { return m_settings.to_json(); }
    bool requires_decoupled() const override { return m_settings.accepts == "decoupled"; }
    /// The program gets the snapshot as the suite gives it (version 2, friction included); it
    /// solved the frictional problem when it returns lambda_t too, else the relaxation (runner.hpp).
    bool handles_friction() const override { return true; }
    SolverResult solve(const QpView& qp, const SolveContext& context) override;

private:
    CommandSettings m_settings;
};

SolverEntry command_entry();

/// simulate and chains run a `command` solver (an external program) only when the scene says
/// "allow_commands": true and the command line gives --allow-commands: a scene file alone, which
/// may come from anywhere, never starts a program, nor does a habitual flag start one that the
/// scene did not declare. InputError naming the scene file and its field otherwise.
void require_command_opt_in(const std::string& solver, const std::string& scene_file, bool scene_allows,
                            bool flag_given);

/// Adds `command` to builtin_registry() (add_builtin_registration); call before its first use.
/// Idempotent.
void install_command_solver();

}  // namespace cb
