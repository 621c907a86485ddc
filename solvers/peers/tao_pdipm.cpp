// PETSc TAO's TAOPDIPM as an external peer, run in a child process (see tao_pdipm.hpp).
#include "solvers/peers/tao_pdipm.hpp"
#include "solvers/core/solve_loop.hpp"
#include "solvers/linalg/a_product.hpp"
#include "solvers/measure/accuracy.hpp"
#include "solvers/peers/child_process.hpp"
#include "solvers/peers/siconos_report.hpp"
#include "solvers/peers/tao_common.hpp"

#include <algorithm>
#include <cstring>
#include <sstream>
#include <vector>

namespace cb {

namespace {

/// Its own settings, declared once (settings.hpp SettingsTable); the common block comes first.
const SettingsTable<TaoPdipmSettings>& tao_pdipm_settings_table()
{
    static const SettingsTable<TaoPdipmSettings> table = SettingsTable<TaoPdipmSettings>();
    return table;
}

}  // namespace

TaoPdipmSettings TaoPdipmSettings::from_json(const nlohmann::json& settings)
{
    return read_settings(settings, "tao-pdipm", tao_pdipm_settings_table());
}

nlohmann::json TaoPdipmSettings::to_json() const { return write_settings(*this, tao_pdipm_settings_table()); }

namespace {

// PETSc's Vec and Mat are the global ::Vec and ::Mat here (cb::Vec is Eigen's).
struct TaoQp {
    const QpView* qp;
};

PetscErrorCode inequalities(Tao, ::Vec X, ::Vec C, void* ctx)
{
    const QpView& qp = *static_cast<TaoQp*>(ctx)->qp;
    const PetscScalar* x;
    PetscScalar* c;
    PetscFunctionBeginUser;
    PetscCall(VecGetArrayRead(X, &x));
    PetscCall(VecGetArray(C, &c));
    Eigen::Map<cb::Vec>(c, qp.m()) = qp.J * Eigen::Map<const cb::Vec>(x, qp.n()) - qp.c;
    PetscCall(VecRestoreArray(C, &c));
    PetscCall(VecRestoreArrayRead(X, &x));
    PetscFunctionReturn(0);
}

PetscErrorCode inequality_jacobian(Tao, ::Vec, Mat, Mat, void*) { return 0; }  // constant: J

constexpr long ITERATION_CAP = 200;

/// Objective evaluations at one TAO iteration number before the solve is ended as stuck: a PDIPM
/// iteration takes 2 or 3 (SNES's function, the line search's residual); a failing inner SNES
/// takes 1 per retry and retries forever.
constexpr long STUCK_EVALUATIONS = 50;

struct TaoRun : tao::Outcome {
    long stuck_iteration = 0;
    long max_evaluations_at_iteration = 0;
};

/// PDIPM's inequality multipliers (no variable bound is finite, so these are Jx - c >= 0's).
PetscErrorCode duals(Tao tao, Eigen::Index m, cb::Vec& lambda)
{
    ::Vec DE = nullptr, DI = nullptr;
    PetscFunctionBeginUser;
    PetscCall(TaoGetDualVariables(tao, &DE, &DI));
    lambda = cb::Vec::Zero(m);
    if (DI) {
        PetscInt size;
        const PetscScalar* l;
        PetscCall(VecGetSize(DI, &size));
        PetscCall(VecGetArrayRead(DI, &l));
        for (PetscInt i = 0; i < std::min<PetscInt>(size, static_cast<PetscInt>(m)); ++i) lambda[i] = l[i];
        PetscCall(VecRestoreArrayRead(DI, &l));
    }
    PetscFunctionReturn(0);
}

/// One TAOPDIPM solve from qp.x0 with gatol = catol = `tol_tao`, under stop=kkt (`common`) ended
/// at the first iterate where the loop's rule holds (tao::KktTest); x and lambda (m) out.
PetscErrorCode pdipm(const QpView& qp, const CommonSettings& common, const SolveLoop& loop, double tol_tao,
                     cb::Vec& x_out, cb::Vec& lambda_out, TaoRun& run)
{
    const long max_iterations = common.max_iterations;
    const PetscInt n = static_cast<PetscInt>(qp.n()), m = static_cast<PetscInt>(qp.m());
    TaoQp ctx{&qp};
    tao::Objective objective;
    objective.qp = &qp;
    objective.stuck_limit = STUCK_EVALUATIONS;
    Tao tao;
    ::Vec X, XL, XU, C;
    tao::KktTest kkt;
    Mat H, JC;
    PetscFunctionBeginUser;
    PetscCall(tao::aij(qp.A, &H));
    PetscCall(tao::aij(qp.J, &JC));
    PetscCall(VecCreateSeq(PETSC_COMM_SELF, n, &X));
    PetscCall(VecDuplicate(X, &XL));
    PetscCall(VecDuplicate(X, &XU));
    PetscCall(VecSet(XL, PETSC_NINFINITY));
    PetscCall(VecSet(XU, PETSC_INFINITY));
    PetscCall(VecCreateSeq(PETSC_COMM_SELF, m, &C));
    PetscCall(tao::to_petsc(qp.x0, X));

    PetscCall(TaoCreate(PETSC_COMM_SELF, &tao));
    PetscCall(TaoSetType(tao, TAOPDIPM));
    PetscCall(TaoSetSolution(tao, X));
    PetscCall(TaoSetVariableBounds(tao, XL, XU));
    PetscCall(TaoSetObjectiveAndGradient(tao, nullptr, tao::objective_and_gradient, &objective));
    PetscCall(TaoSetHessian(tao, H, H, tao::constant_hessian, nullptr));
    PetscCall(TaoSetInequalityConstraintsRoutine(tao, C, inequalities, &ctx));
    PetscCall(TaoSetJacobianInequalityRoutine(tao, JC, JC, inequality_jacobian, &ctx));
    PetscCall(TaoSetTolerances(tao, tol_tao, 0.0, 0.0));
    PetscCall(TaoSetConstraintTolerances(tao, tol_tao, 0.0));
    // An interior point converges in tens of iterations; at an absolute tolerance beyond its
    // reach TAOPDIPM iterates without end, so it is capped (the cap is `stalled`, not max_iterations).
    const long cap = std::min<long>(max_iterations, ITERATION_CAP);
    PetscCall(TaoSetMaximumIterations(tao, static_cast<PetscInt>(cap)));
    if (!common.stops_on_native()) {
        kkt.qp = &qp;
        kkt.loop = &loop;
        kkt.scale = accuracy_scale(qp);
        kkt.multipliers = [&qp](Tao t, const cb::Vec&, cb::Vec& lambda) { return duals(t, qp.m(), lambda); };
        PetscCall(TaoSetConvergenceTest(tao, tao::kkt_convergence_test, &kkt));
    }
    PetscCall(TaoSetFromOptions(tao));  // the -ksp/-pc options set by run_pdipm
    PetscCall(TaoSolve(tao));

    PetscInt its;
    PetscReal f, gnorm, cnorm, xdiff;
    TaoConvergedReason reason;
    PetscCall(TaoGetSolutionStatus(tao, &its, &f, &gnorm, &cnorm, &xdiff, &reason));
    run.reason = static_cast<int>(reason);
    run.report.info = reason > 0 ? 0 : static_cast<int>(reason);
    run.report.iterations += static_cast<int>(its);
    run.report.residual = std::max(gnorm, cnorm);
    run.report.max_iterations_reached = reason == TAO_DIVERGED_MAXITS && cap == max_iterations;
    run.stuck = objective.stuck;
    run.stuck_iteration = static_cast<long>(its);
    run.evaluations += objective.evaluations;
    run.max_evaluations_at_iteration =
        std::max(run.max_evaluations_at_iteration, objective.max_evaluations_at_iteration);
    PetscCall(tao::from_petsc(X, x_out));
    PetscCall(duals(tao, qp.m(), lambda_out));
    run.kkt_met = kkt.met;
    run.kkt_checks = kkt.checks;
    PetscCall(TaoDestroy(&tao));
    PetscCall(MatDestroy(&H));
    PetscCall(MatDestroy(&JC));
    PetscCall(VecDestroy(&X));
    PetscCall(VecDestroy(&XL));
    PetscCall(VecDestroy(&XU));
    PetscCall(VecDestroy(&C));
    PetscFunctionReturn(0);
}

/// In the child (a fork: `loop` is its copy of the parent's): returns x (n doubles), lambda (m
/// doubles), then a TaoRun.
std::vector<char> run_pdipm(const QpView& qp, const CommonSettings& common, const SolveLoop& loop,
                            const std::string& session_folder)
{
    const Eigen::Index n = qp.n(), m = qp.m();
    cb::Vec x = qp.x0, lambda = cb::Vec::Zero(m);
    TaoRun run;
    // A direct inner solver: the default GMRES + ILU fails on stiff problems.
    if (tao::start_petsc(session_folder) && PetscOptionsSetValue(nullptr, "-ksp_type", "preonly") == 0 &&
        PetscOptionsSetValue(nullptr, "-pc_type", "lu") == 0 &&
#ifdef PETSC_HAVE_MUMPS
        PetscOptionsSetValue(nullptr, "-pc_factor_mat_solver_type", "mumps") == 0 &&
#endif
        true) {
        // stop=kkt: the harness's test ends the solve, not TAO's absolute tolerances (0: off), which
        // do not scale with the problem; the iteration cap and time limit bound a run that never meets it.
        run.gatol = common.stops_on_native() ? common.tol : 0.0;
        const PetscErrorCode ierr = pdipm(qp, common, loop, run.gatol, x, lambda, run);
        if (ierr != 0) run.report.info = -1000 - static_cast<int>(ierr);
        PetscFinalize();
    } else {
        run.report.info = -2000;
    }
    std::vector<char> out(static_cast<size_t>(n + m) * sizeof(double) + sizeof run);
    std::memcpy(out.data(), x.data(), static_cast<size_t>(n) * sizeof(double));
    std::memcpy(out.data() + n * sizeof(double), lambda.data(), static_cast<size_t>(m) * sizeof(double));
    std::memcpy(out.data() + (n + m) * sizeof(double), &run, sizeof run);
    return out;
}

}  // namespace

SolverResult TaoPdipmSolver::solve(const QpView& qp, const SolveContext& context)
{
    const TaoPdipmSettings& s = m_settings;
    const Eigen::Index n = qp.n(), m = qp.m();
    SolverResult result;
    Counters& counters = result.counters;
    result.x = qp.x0;
    result.lambda = cb::Vec::Zero(m);
    result.info["library"] = "PETSc " PETSC_VERSION_STRING_CB;
    result.info["history"] = "final point only (TAO's monitor is not forwarded from the child process)";
    result.info["child_process"] = true;
    result.info["native_residual_definition"] = "max of TAO's gradient norm and constraint norm";
#ifdef PETSC_HAVE_MUMPS
    const char* factor = "mumps";
#else
    const char* factor = "petsc";
#endif
    result.info["tao_options"] = {{"tao_type", "pdipm"},
                                  {"ksp_type", "preonly"},
                                  {"pc_type", "lu"},
                                  {"pc_factor_mat_solver_type", factor},
                                  {"variable_bounds", "-inf, +inf"}};
    SolveLoop loop("tao-pdipm", qp, s.common, context);  // no setup: the child does all the work
    loop.end_setup();
    if (!loop.inputs_finite())  // the library would abort on it (seen: Siconos's assertions)
        return loop.finish(result, loop.check(counters.iterations, false, false), "PETSc not called");
    const size_t expected = static_cast<size_t>(n + m) * sizeof(double) + sizeof(TaoRun);
    const tao::SessionFolder session;  // removed when the solve returns, after the child ended
    const ChildOutcome child = run_in_child([&]() { return run_pdipm(qp, s.common, loop, session.path()); },
                                            loop.stopwatch(), s.common.time_limit_s);
    if (auto failed = finish_failed_child(child, expected, "PETSc", loop, result)) return std::move(*failed);
    const char* p = child.bytes.data();
    std::memcpy(result.x.data(), p, static_cast<size_t>(n) * sizeof(double));
    std::memcpy(result.lambda.data(), p + n * sizeof(double), static_cast<size_t>(m) * sizeof(double));
    TaoRun run;
    std::memcpy(&run, p + (n + m) * sizeof(double), sizeof run);
    counters.iterations = run.report.iterations;
    // one A x per objective and gradient evaluation and per harness test in TAO's convergence test
    counters.a_products += run.evaluations + run.kkt_checks;
    std::ostringstream stuck;
    stuck << "TAOPDIPM's Newton step failed " << STUCK_EVALUATIONS << " times in a row at iteration "
          << run.stuck_iteration
          << ", its inner SNES reporting DIVERGED_LINEAR_SOLVE, and TAOPDIPM retries without end";
    return tao::finish_result(qp, s.common, loop, run, "TAOPDIPM", stuck.str(), counters, result);
}

SolverEntry tao_pdipm_entry()
{
    SolverEntry e = solver_entry<TaoPdipmSolver>(
        "tao-pdipm", tao_pdipm_settings_table(),
        "peer: PETSc " PETSC_VERSION_STRING_CB
        " TAO primal-dual interior point (TAOPDIPM, direct LU inner solves) on the primal QP (child process)",
        "any J (interior point on the primal QP)");
    e.library = "PETSc " PETSC_VERSION_STRING_CB;
    return e;
}

}  // namespace cb
