// PETSc TAO's TAOTRON as an external peer on bound rows, run in a child process (see tao_tron.hpp).
#include "solvers/peers/tao_tron.hpp"
#include "solvers/core/solve_loop.hpp"
#include "solvers/linalg/a_product.hpp"
#include "solvers/measure/accuracy.hpp"
#include "solvers/mprgp/bounds.hpp"
#include "solvers/peers/child_process.hpp"
#include "solvers/peers/siconos_report.hpp"
#include "solvers/peers/tao_common.hpp"

#include <algorithm>
#include <cstring>
#include <limits>
#include <sstream>
#include <vector>

namespace cb {

namespace {

/// Its own settings, declared once (settings.hpp SettingsTable); the common block comes first.
const SettingsTable<TaoTronSettings>& tao_tron_settings_table()
{
    static const SettingsTable<TaoTronSettings> table = SettingsTable<TaoTronSettings>();
    return table;
}

}  // namespace

TaoTronSettings TaoTronSettings::from_json(const nlohmann::json& settings)
{
    return read_settings(settings, "tao-tron", tao_tron_settings_table());
}

nlohmann::json TaoTronSettings::to_json() const { return write_settings(*this, tao_tron_settings_table()); }

namespace {

using Bounds = RowBounds;  // solvers/mprgp/bounds.hpp: the rows read as bounds, one policy

/// TRON's multipliers are not returned: at its point, the gradient g_j of a DOF at a bound is the
/// binding row's force (bound_multipliers).
cb::Vec multipliers(const QpView& qp, const Bounds& b, const cb::Vec& x)
{
    return bound_multipliers(qp, b, a_product(qp.A, x) - qp.b);
}

/// Objective evaluations at one TRON iteration before the solve is ended as stuck: TRON shrinks
/// its trust region and re-evaluates while a step is rejected; that ends by itself once the
/// radius is below its step tolerance, and this guard only bounds a loop that would not.
constexpr long STUCK_EVALUATIONS = 200;

using TronRun = tao::Outcome;

/// One TAOTRON solve from qp.x0 (projected onto the bounds by TRON) with gatol = `tol_tao`, under
/// stop=kkt ended at the first iterate where the loop's rule holds (tao::KktTest).
PetscErrorCode tron(const QpView& qp, const Bounds& bounds, const CommonSettings& common, const SolveLoop& loop,
                    double tol_tao, cb::Vec& x_out, TronRun& run)
{
    const long max_iterations = common.max_iterations;
    tao::KktTest kkt;
    const PetscInt n = static_cast<PetscInt>(qp.n());
    tao::Objective objective;
    objective.qp = &qp;
    objective.stuck_limit = STUCK_EVALUATIONS;
    Tao tao;
    ::Vec X, XL, XU;
    Mat H;
    PetscFunctionBeginUser;
    PetscCall(tao::aij(qp.A, &H));
    PetscCall(VecCreateSeq(PETSC_COMM_SELF, n, &X));
    PetscCall(VecDuplicate(X, &XL));
    PetscCall(VecDuplicate(X, &XU));
    PetscCall(tao::to_petsc(qp.x0, X));
    PetscCall(tao::to_petsc(bounds.lower, XL));
    PetscCall(tao::to_petsc(bounds.upper, XU));
    PetscCall(TaoCreate(PETSC_COMM_SELF, &tao));
    PetscCall(TaoSetType(tao, TAOTRON));
    PetscCall(TaoSetSolution(tao, X));
    PetscCall(TaoSetVariableBounds(tao, XL, XU));
    PetscCall(TaoSetObjectiveAndGradient(tao, nullptr, tao::objective_and_gradient, &objective));
    PetscCall(TaoSetHessian(tao, H, H, tao::constant_hessian, nullptr));
    PetscCall(TaoSetTolerances(tao, tol_tao, 0.0, 0.0));
    PetscCall(TaoSetMaximumIterations(tao, static_cast<PetscInt>(std::min<long>(max_iterations, 1L << 30))));
    // TAO's default cap of 4000 evaluations would end long runs before max_iterations does.
    PetscCall(TaoSetMaximumFunctionEvaluations(
        tao, static_cast<PetscInt>(std::min<long>(20 * max_iterations + 100, 1L << 30))));
    // Jacobi on TRON's trust-region CG (as mprgp-box's default): with PETSc's default ILU(0) TRON
    // did not finish its first iteration in 120 s on the stress case dino-stiff-1e10 (E = 1e10,
    // n = 3909); with Jacobi it converges in 1.5 s.
    KSP ksp;
    PC pc;
    PetscCall(TaoGetKSP(tao, &ksp));
    PetscCall(KSPGetPC(ksp, &pc));
    PetscCall(PCSetType(pc, PCJACOBI));
    if (!common.stops_on_native()) {
        kkt.qp = &qp;
        kkt.loop = &loop;
        kkt.scale = accuracy_scale(qp);
        kkt.multipliers = [&qp, &bounds](Tao, const cb::Vec& x, cb::Vec& lambda) -> PetscErrorCode {
            lambda = multipliers(qp, bounds, x);
            return 0;
        };
        PetscCall(TaoSetConvergenceTest(tao, tao::kkt_convergence_test, &kkt));
    }
    PetscCall(TaoSetFromOptions(tao));
    PetscCall(TaoSolve(tao));

    PetscInt its;
    PetscReal f, gnorm, cnorm, xdiff;
    TaoConvergedReason reason;
    PetscCall(TaoGetSolutionStatus(tao, &its, &f, &gnorm, &cnorm, &xdiff, &reason));
    run.reason = static_cast<int>(reason);
    run.report.info = reason > 0 ? 0 : static_cast<int>(reason);
    run.report.iterations += static_cast<int>(its);
    run.report.residual = gnorm;
    run.report.max_iterations_reached = reason == TAO_DIVERGED_MAXITS;
    run.stuck = objective.stuck;
    run.evaluations += objective.evaluations;
    run.kkt_met = kkt.met;
    run.kkt_checks = kkt.checks;
    PetscCall(tao::from_petsc(X, x_out));
    PetscCall(TaoDestroy(&tao));
    PetscCall(MatDestroy(&H));
    PetscCall(VecDestroy(&X));
    PetscCall(VecDestroy(&XL));
    PetscCall(VecDestroy(&XU));
    PetscFunctionReturn(0);
}

/// In the child (a fork: `loop` is its copy of the parent's): returns x (n doubles), then a TronRun.
std::vector<char> run_tron(const QpView& qp, const Bounds& bounds, const CommonSettings& common, const SolveLoop& loop,
                           const std::string& session_folder)
{
    const Eigen::Index n = qp.n();
    cb::Vec x = qp.x0;
    TronRun run;
    if (tao::start_petsc(session_folder)) {
        // stop=kkt: the harness's test ends the solve, not TAO's absolute tolerances (0: off), which
        // do not scale with the problem; the iteration cap and time limit bound a run that never meets it.
        run.gatol = common.stops_on_native() ? common.tol : 0.0;
        const PetscErrorCode ierr = tron(qp, bounds, common, loop, run.gatol, x, run);
        if (ierr != 0) run.report.info = -1000 - static_cast<int>(ierr);
        PetscFinalize();
    } else {
        run.report.info = -2000;
    }
    std::vector<char> out(static_cast<size_t>(n) * sizeof(double) + sizeof run);
    std::memcpy(out.data(), x.data(), static_cast<size_t>(n) * sizeof(double));
    std::memcpy(out.data() + n * sizeof(double), &run, sizeof run);
    return out;
}

}  // namespace

SolverResult TaoTronSolver::solve(const QpView& qp, const SolveContext& context)
{
    const TaoTronSettings& s = m_settings;
    const Eigen::Index n = qp.n(), m = qp.m();
    SolverResult result;
    Counters& counters = result.counters;
    result.x = qp.x0;
    result.lambda = cb::Vec::Zero(m);
    result.info["library"] = "PETSc " PETSC_VERSION_STRING_CB;
    result.info["history"] = "final point only (TAO's monitor is not forwarded from the child process)";
    result.info["child_process"] = true;
    result.info["native_residual_definition"] = "TAO's projected gradient norm";
    result.info["lambda"] = "from the gradient at TRON's point (g_j / a on the binding bound row)";
    result.info["tao_options"] = {{"tao_type", "tron"}, {"pc_type", "jacobi"}};
    SolveLoop loop("tao-tron", qp, s.common, context);
    const Bounds bounds = bounds_from_rows(qp);
    if (bounds.status != SolveStatus::NOT_RUN)
        return loop.finish(result, bounds.status,
                           "tao-tron: " + bounds.why +
                               (bounds.status == SolveStatus::NOT_APPLICABLE ? "; use tao-pdipm (any J)" : ""));
    loop.end_setup();
    if (!loop.inputs_finite())  // the library would abort on it (seen: Siconos's assertions)
        return loop.finish(result, loop.check(counters.iterations, false, false), "PETSc not called");
    const size_t expected = static_cast<size_t>(n) * sizeof(double) + sizeof(TronRun);
    const tao::SessionFolder session;  // removed when the solve returns, after the child ended
    const ChildOutcome child = run_in_child([&]() { return run_tron(qp, bounds, s.common, loop, session.path()); },
                                            loop.stopwatch(), s.common.time_limit_s);
    if (auto failed = finish_failed_child(child, expected, "PETSc", loop, result)) return std::move(*failed);
    std::memcpy(result.x.data(), child.bytes.data(), static_cast<size_t>(n) * sizeof(double));
    TronRun run;
    std::memcpy(&run, child.bytes.data() + n * sizeof(double), sizeof run);
    result.lambda = multipliers(qp, bounds, result.x);
    // the multipliers' gradient; one A x per evaluation and per harness test in TAO's convergence test
    counters.a_products += 1 + run.evaluations + 2 * run.kkt_checks;
    counters.iterations = run.report.iterations;
    std::ostringstream stuck;
    stuck << STUCK_EVALUATIONS << " objective evaluations at iteration " << run.report.iterations;
    return tao::finish_result(qp, s.common, loop, run, "TAOTRON", stuck.str(), counters, result);
}

SolverEntry tao_tron_entry()
{
    SolverEntry e = solver_entry<TaoTronSolver>(
        "tao-tron", tao_tron_settings_table(),
        "peer: PETSc " PETSC_VERSION_STRING_CB
        " TAO TRON (Newton trust region for bound constraints) on bound rows (child process)",
        "bounds only (every row of J has at most one nonzero)");
    e.library = "PETSc " PETSC_VERSION_STRING_CB;
    return e;
}

}  // namespace cb
