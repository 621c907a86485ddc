// Shared pieces of the PETSc TAO peers (see tao_common.hpp).
#include "solvers/peers/tao_common.hpp"
#include "solvers/core/solver.hpp"
#include "solvers/linalg/a_product.hpp"
#include "solvers/measure/accuracy.hpp"

#include <fcntl.h>
#include <stdlib.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace cb::tao {

SessionFolder::SessionFolder()
{
    std::string pattern = (std::filesystem::temp_directory_path() / "contactbench-mpi-XXXXXX").string();
    if (!::mkdtemp(pattern.data()))
        throw std::runtime_error("tao: cannot create a session folder " + pattern + ": " + std::strerror(errno));
    m_path = pattern;
}

SessionFolder::~SessionFolder()
{
    std::error_code ignored;  // a folder that cannot be removed is left behind, never an exception here
    std::filesystem::remove_all(m_path, ignored);
}

bool start_petsc(const std::string& session_folder)
{
    // Only this child's environment changes (it is a fork): the parent's stays as it was.
    if (::setenv("TMPDIR", session_folder.c_str(), 1) != 0 ||
        ::setenv("OMPI_MCA_orte_tmpdir_base", session_folder.c_str(), 1) != 0)
        return false;
    // dup2 on the descriptor, not freopen: freopen would flush the stdio buffer inherited from the
    // parent and print the parent's pending output twice.
    const int devnull = ::open("/dev/null", O_WRONLY);
    if (devnull >= 0) {
        ::dup2(devnull, STDOUT_FILENO);
        ::close(devnull);
    }
    if (PetscInitializeNoArguments() != 0) return false;
    // Errors come back as codes (the message gives the code) instead of PETSc's page of
    // traceback and configure options on stderr for every failed MUMPS solve.
    return PetscPushErrorHandler(PetscReturnErrorHandler, nullptr) == 0;
}

PetscErrorCode aij(const SpMat& S, Mat* out)
{
    // SpMat is row-major: its compressed arrays are CSR already (a copy only when uncompressed).
    SpMat copy;
    if (!S.isCompressed()) {
        copy = S;
        copy.makeCompressed();
    }
    const SpMat& R = S.isCompressed() ? S : copy;
    std::vector<PetscInt> rows(static_cast<size_t>(R.rows()) + 1), cols(static_cast<size_t>(R.nonZeros()));
    for (Eigen::Index i = 0; i <= R.rows(); ++i) rows[static_cast<size_t>(i)] = R.outerIndexPtr()[i];
    for (Eigen::Index k = 0; k < R.nonZeros(); ++k) cols[static_cast<size_t>(k)] = R.innerIndexPtr()[k];
    PetscFunctionBeginUser;
    PetscCall(MatCreate(PETSC_COMM_SELF, out));
    PetscCall(MatSetSizes(*out, static_cast<PetscInt>(R.rows()), static_cast<PetscInt>(R.cols()),
                          static_cast<PetscInt>(R.rows()), static_cast<PetscInt>(R.cols())));
    PetscCall(MatSetType(*out, MATSEQAIJ));
    PetscCall(MatSeqAIJSetPreallocationCSR(*out, rows.data(), cols.data(), R.valuePtr()));
    PetscFunctionReturn(0);
}

PetscErrorCode to_petsc(const cb::Vec& v, ::Vec V)
{
    PetscScalar* p;
    PetscFunctionBeginUser;
    PetscCall(VecGetArray(V, &p));
    Eigen::Map<cb::Vec>(p, v.size()) = v;
    PetscCall(VecRestoreArray(V, &p));
    PetscFunctionReturn(0);
}

PetscErrorCode from_petsc(::Vec V, cb::Vec& v)
{
    PetscInt size;
    const PetscScalar* p;
    PetscFunctionBeginUser;
    PetscCall(VecGetSize(V, &size));
    PetscCall(VecGetArrayRead(V, &p));
    v = Eigen::Map<const cb::Vec>(p, size);
    PetscCall(VecRestoreArrayRead(V, &p));
    PetscFunctionReturn(0);
}

PetscErrorCode objective_and_gradient(Tao tao, ::Vec X, PetscReal* f, ::Vec G, void* ctx)
{
    Objective& o = *static_cast<Objective*>(ctx);
    const QpView& qp = *o.qp;
    const PetscScalar* x;
    PetscScalar* g;
    PetscInt iteration;
    PetscFunctionBeginUser;
    PetscCall(TaoGetIterationNumber(tao, &iteration));
    ++o.evaluations;
    if (iteration != o.iteration) {
        o.iteration = iteration;
        o.evaluations_at_iteration = 0;
    }
    ++o.evaluations_at_iteration;
    if (o.evaluations_at_iteration > o.max_evaluations_at_iteration)
        o.max_evaluations_at_iteration = o.evaluations_at_iteration;
    if (o.evaluations_at_iteration > o.stuck_limit && !o.stuck) {
        o.stuck = true;
        PetscCall(TaoSetConvergedReason(tao, TAO_DIVERGED_USER));
    }
    PetscCall(VecGetArrayRead(X, &x));
    PetscCall(VecGetArray(G, &g));
    const Eigen::Map<const cb::Vec> xv(x, qp.n());
    Eigen::Map<cb::Vec> gv(g, qp.n());
    gv = qp.A * xv;
    *f = 0.5 * xv.dot(gv) - qp.b.dot(xv);
    gv -= qp.b;
    PetscCall(VecRestoreArray(G, &g));
    PetscCall(VecRestoreArrayRead(X, &x));
    PetscFunctionReturn(0);
}

bool fit_multipliers_where_rule_holds(const QpView& qp, const SolveLoop& loop, const cb::Vec& x, cb::Vec& lambda)
{
    if (!x.allFinite()) return false;
    const AccuracyScale scale = accuracy_scale(qp);
    cb::Vec g;  // formed on the first evaluation: under stop=native none is made
    const auto error_with = [&](const cb::Vec& multipliers) {
        if (g.size() == 0) g = a_product(qp.A, x) - qp.b;
        return multipliers.allFinite() ? accuracy_from_gradient(qp, scale, x, g, multipliers).max()
                                       : std::numeric_limits<double>::infinity();
    };
    // `true` as the native measure: under stop=native the multipliers are not what the rule reads.
    if (loop.rule_holds(true, [&] { return error_with(lambda); })) return false;
    cb::Vec fit = fit_multipliers(qp, scale, x, g);
    if (!loop.rule_holds(true, [&] { return error_with(fit); })) return false;
    lambda = std::move(fit);
    return true;
}

PetscErrorCode kkt_convergence_test(Tao tao, void* ctx)
{
    KktTest& t = *static_cast<KktTest*>(ctx);
    const QpView& qp = *t.qp;
    ::Vec X;
    cb::Vec x, lambda = cb::Vec::Zero(qp.m());
    PetscFunctionBeginUser;
    PetscCall(TaoGetSolution(tao, &X));
    PetscCall(from_petsc(X, x));
    PetscCall(t.multipliers(tao, x, lambda));
    ++t.checks;
    // TAO's own test, not a native measure of ours, is the native rule: +inf (not met) here.
    const bool met =
        x.allFinite() && lambda.allFinite() && t.loop->rule_holds(std::numeric_limits<double>::infinity(), [&] {
            const cb::Vec g = a_product(qp.A, x) - qp.b;
            return accuracy_from_gradient(qp, t.scale, x, g, lambda).max();
        });
    if (met) {
        t.met = true;
        PetscCall(TaoSetConvergedReason(tao, TAO_CONVERGED_USER));
        PetscFunctionReturn(0);
    }
    PetscCall(TaoDefaultConvergenceTest(tao, nullptr));
    PetscFunctionReturn(0);
}

PetscErrorCode constant_hessian(Tao, ::Vec, Mat, Mat, void*) { return 0; }

SolverResult finish_result(const QpView& qp, const CommonSettings& common, SolveLoop& loop, const Outcome& run,
                           const std::string& what, const std::string& stuck_text, Counters& counters,
                           SolverResult& result)
{
    result.info["tao_reason"] = TaoConvergedReasons[run.reason];
    result.info["tao_gatol"] = run.gatol;
    result.info["kkt_test_in_tao"] = !common.stops_on_native();
    result.info["tao_stuck"] = run.stuck;
    result.info["objective_evaluations"] = run.evaluations;
    // The verdict judges the point: where TAO's multipliers miss tol, fitted ones are tried.
    result.info["lambda_fitted"] = fit_multipliers_where_rule_holds(qp, loop, result.x, result.lambda);
    std::ostringstream msg;
    msg << "; TAO reason " << TaoConvergedReasons[run.reason];
    if (run.report.info <= -2000)
        msg << " (PETSc did not start)";
    else if (run.report.info <= -1000) {
        const int code = -1000 - run.report.info;
        const char* text = nullptr;  // PETSc's static table: no PetscInitialize needed
        PetscErrorMessage(static_cast<PetscErrorCode>(code), &text, nullptr);
        msg << " (TaoSolve stopped on PETSc error " << code << ": " << (text ? text : "unknown") << ")";
    }
    if (run.kkt_met) msg << " (set by the harness: its accuracy test met tol at TAO's iterate)";
    if (run.stuck) msg << " (set by the harness: " << stuck_text << ")";
    return finish_siconos_result(qp, loop, run.report, what, "iterations", counters, result, msg.str());
}

}  // namespace cb::tao
