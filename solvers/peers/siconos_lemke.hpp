#pragma once
/// `siconos-lemke`: an external peer, Siconos numerics' lexicographic Lemke (SICONOS_LCP_LEMKE)
/// on the harness's own dual LCP
///   w = W lambda + q >= 0,  lambda >= 0,  lambda'w = 0,   W = J A^-1 J',  q = J A^-1 b - c,
/// with W formed densely by CHOLMOD (counted as setup, like `pgs`) and x = A^-1 (b + J'lambda).
/// Compiled only when CMake finds libsiconos_numerics (find_library/find_path: Debian ships no
/// .pc file and its CMake config fails). Siconos solvers can abort or segfault, so the pivoting
/// runs in a forked child process: a crash is recorded as status `diverged` with the signal in the
/// message and info.crashed = true, and time_limit_s ends the child (status `time_limit`).
/// The verdict is the common KKT test at the returned point; Siconos's info code goes to the message.
#include "solvers/core/registry.hpp"
#include "solvers/core/solver.hpp"

namespace cb {

struct SiconosLemkeSettings {
    CommonSettings common;
    long max_rows = 4000;  ///< refuse problems with m > max_rows (W is dense m x m)

    static SiconosLemkeSettings from_json(const nlohmann::json& settings);  ///< throws InputError
    nlohmann::json to_json() const;
};

class SiconosLemkeSolver : public Solver {
public:
    explicit SiconosLemkeSolver(SiconosLemkeSettings settings) : m_settings(settings) {}
    std::string name() const override { return "siconos-lemke"; }
    nlohmann::json settings() const override { return m_settings.to_json(); }
    SolverResult solve(const QpView& qp, const SolveContext& context) override;

private:
    SiconosLemkeSettings m_settings;
};

SolverEntry siconos_lemke_entry();

}  // namespace cb
