#pragma once
/// What the PETSc TAO peers (`tao-pdipm`, `tao-tron`) share, inside their child process: PETSc's
/// start, the QP's objective, gradient and constant Hessian as TAO callbacks, sequential AIJ copies
/// of Eigen matrices, and a guard that ends a TAO solve whose iterations no longer advance.
/// Only the TAO peers' sources include this header (they are compiled with PETSc's flags).
#include "solvers/core/qp.hpp"

#include "solvers/measure/accuracy.hpp"
#include "solvers/peers/siconos_report.hpp"

#include <petsctao.h>

#include <functional>
#include <string>

namespace cb::tao {

/// A fresh folder for one TAO child's Open MPI session files (mkdtemp under the system's temporary
/// folder: $TMPDIR, else /tmp), removed with its contents on destruction. Two children that start
/// Open MPI at once otherwise share its one session folder /tmp/ompi.<host>.<uid>, and one of them
/// can abort in MPI_Init_thread ("mkdir ... File exists"; docs/peers.md). Made in the parent
/// before the fork and destroyed there after the child ended. Throws std::runtime_error when the
/// folder cannot be made.
class SessionFolder {
public:
    SessionFolder();
    ~SessionFolder();
    SessionFolder(const SessionFolder&) = delete;
    SessionFolder& operator=(const SessionFolder&) = delete;
    const std::string& path() const { return m_path; }

private:
    std::string m_path;
};

/// In the child process: points Open MPI's session folder at `session_folder` (TMPDIR and
/// OMPI_MCA_orte_tmpdir_base, both read by Open MPI 4.1; the singleton's orted inherits them), sends
/// stdout to /dev/null (TAOPDIPM prints each failed inner SNES solve there, which would interleave
/// with the harness's output), initialises PETSc (and an Open MPI singleton) and makes PETSc errors
/// return their code without printing. False when PETSc did not start.
bool start_petsc(const std::string& session_folder);

/// A sequential AIJ copy of S.
PetscErrorCode aij(const SpMat& S, Mat* out);

/// v's entries (size v.size()) into the PETSc vector V, and back.
PetscErrorCode to_petsc(const cb::Vec& v, ::Vec V);
PetscErrorCode from_petsc(::Vec V, cb::Vec& v);

/// The context of objective_and_gradient. TAOPDIPM calls its inner SNES again and again from the
/// same point when the Newton step's linear solve fails, without counting an iteration or testing
/// its caps; every SNES call evaluates the objective, so the callback sees it: after `stuck_limit`
/// evaluations at the same TAO iteration number it sets TAO's reason to TAO_DIVERGED_USER, which
/// ends TaoSolve's loop.
struct Objective {
    const QpView* qp = nullptr;
    long stuck_limit = 50;
    long evaluations = 0;               ///< in all
    long evaluations_at_iteration = 0;  ///< since TAO's iteration number last changed
    long max_evaluations_at_iteration = 0;
    PetscInt iteration = -1;
    bool stuck = false;  ///< the guard ended the solve
};

/// f = 1/2 x'Ax - b'x, g = Ax - b; `ctx` is an Objective.
PetscErrorCode objective_and_gradient(Tao tao, ::Vec X, PetscReal* f, ::Vec G, void* ctx);

/// In the parent, before the loop's verdict (docs/accuracy.md: e judges x): when the loop's rule
/// does not hold with TAO's multipliers `lambda` at x, multipliers fitted at x (fit_multipliers)
/// replace them if the rule holds with those; true then. TAO's duals can miss tol at a point that
/// meets it. Under stop=native the rule reads TAO's residual, not the multipliers: nothing changes.
bool fit_multipliers_where_rule_holds(const QpView& qp, const SolveLoop& loop, const cb::Vec& x, cb::Vec& lambda);

/// TAO's convergence test under stop=kkt (TaoSetConvergenceTest): the loop's rule (rule_holds) at
/// TAO's current iterate, with the multipliers `multipliers` gives for it; when it holds, TAO's
/// reason is set to TAO_CONVERGED_USER and `met` is set. Otherwise TAO's default test runs (its
/// iteration and evaluation caps; the peers set its absolute tolerances to 0 under stop=kkt). TAO's
/// own tolerances are absolute, on its own residual norms: they neither scale with the problem (an
/// objective times 2^-26 is "converged" at x0) nor stop where the common measure is met.
/// It runs in the child process: a fork, which holds a copy of the parent's SolveLoop, so the
/// rule asked is the loop's own (its tol and stop); the parent then judges the returned point
/// through the same loop (finish_result), so an iterate the child stopped at is never taken on
/// the child's word.
struct KktTest {
    const QpView* qp = nullptr;
    const SolveLoop* loop = nullptr;  ///< the child's copy of the parent's loop
    AccuracyScale scale;
    std::function<PetscErrorCode(Tao, const cb::Vec& x, cb::Vec& lambda)> multipliers;
    long checks = 0;  ///< calls (each one A x and one J x)
    bool met = false;
};
PetscErrorCode kkt_convergence_test(Tao tao, void* ctx);

/// What a TAO child sends back after its iterate (plain data: copied through the pipe).
struct Outcome {
    SiconosReport report;
    int reason = 0;  ///< TaoConvergedReason
    double gatol = 0.0;
    bool kkt_met = false;  ///< the harness's test ended the solve (stop=kkt)
    long kkt_checks = 0;
    bool stuck = false;  ///< ended by the guard (Objective)
    long evaluations = 0;
};

/// In the parent, once x and lambda are in `result`: TAO's facts into result.info, the verdict on
/// the point (fitted multipliers where TAO's miss tol), finish_siconos_result, and the
/// message: TAO's reason, a PETSc error by its code, and what the harness set (`stuck_text` says
/// why the guard fired). `what` names the method ("TAOTRON"). Returns the finished result.
SolverResult finish_result(const QpView& qp, const CommonSettings& common, SolveLoop& loop, const Outcome& run,
                           const std::string& what, const std::string& stuck_text, Counters& counters,
                           SolverResult& result);

/// The Hessian is A, copied once: nothing to do.
PetscErrorCode constant_hessian(Tao, ::Vec, Mat, Mat, void*);

}  // namespace cb::tao
