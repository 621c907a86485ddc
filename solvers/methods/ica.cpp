// Ref: Li et al., CGF 2015, Sec. 6.2 (ICA as the comparison method); Otaduy et al. 2009, the
// anticipation LCP; ALGORITHMS.md §6 (the exact iteration implemented here).
#include "solvers/methods/ica.hpp"
#include "solvers/core/solve_loop.hpp"

#include "solvers/linalg/a_product.hpp"
#include "solvers/measure/work_units.hpp"

#include <Eigen/CholmodSupport>
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

namespace cb {

namespace {

/// Every setting of `ica`, declared once (settings.hpp SettingsTable).
const SettingsTable<IcaSettings>& ica_settings_table()
{
    static const SettingsTable<IcaSettings> table =
        SettingsTable<IcaSettings>()
            .integer("pgs_sweeps", &IcaSettings::pgs_sweeps, 1, LONG_MAX,
                     "max projected Gauss-Seidel sweeps per outer iteration")
            .number("pgs_tol", &IcaSettings::pgs_tol, -1e-300, 1e300, "PGS stops when ||dlambda||_2 <= pgs_tol")
            .choice("start", &IcaSettings::start, {"x0", "unconstrained"},
                    "x0 | unconstrained (CHOLMOD solve of A x = b, timed in setup_s, reported in info)");
    return table;
}

}  // namespace

IcaSettings IcaSettings::from_json(const nlohmann::json& settings)
{
    return read_settings(settings, "ica", ica_settings_table());
}

nlohmann::json IcaSettings::to_json() const { return write_settings(*this, ica_settings_table()); }

namespace {

/// The 3x3 vertex-block diagonal of A and its inverse. A last block of size < 3 (n not a
/// multiple of 3) is padded with the identity, which leaves its DOFs untouched.
struct BlockDiagonal {
    std::vector<Eigen::Matrix3d> block, inverse;
    Eigen::Index n = 0;
    Eigen::Index blocks() const { return static_cast<Eigen::Index>(block.size()); }
    Eigen::Index begin(Eigen::Index k) const { return 3 * k; }
    int size(Eigen::Index k) const { return static_cast<int>(std::min<Eigen::Index>(3, n - 3 * k)); }
};

/// @return false when a block is not invertible (A not SPD).
bool build_block_diagonal(const SpMat& A, BlockDiagonal& d, std::string& error)
{
    d.n = A.rows();
    const Eigen::Index nb = (d.n + 2) / 3;
    d.block.assign(static_cast<size_t>(nb), Eigen::Matrix3d::Identity());
    d.inverse.assign(static_cast<size_t>(nb), Eigen::Matrix3d::Identity());
    for (Eigen::Index k = 0; k < nb; ++k) {
        Eigen::Matrix3d& blk = d.block[static_cast<size_t>(k)];
        const int s = d.size(k);
        blk.topLeftCorner(s, s).setZero();
        for (int a = 0; a < s; ++a)
            for (SpMat::InnerIterator it(A, d.begin(k) + a); it; ++it) {
                const Eigen::Index col = it.col() - d.begin(k);
                if (col >= 0 && col < s) blk(a, static_cast<int>(col)) = it.value();
            }
        // Each diagonal block of an SPD matrix is SPD; LLT both inverts it and checks that.
        Eigen::LLT<Eigen::Matrix3d> llt(blk);
        if (llt.info() != Eigen::Success) {
            std::ostringstream s_err;
            s_err << "3x3 diagonal block of vertex " << k << " (rows " << d.begin(k) << ".." << d.begin(k) + s - 1
                  << ") is not positive definite";
            error = s_err.str();
            return false;
        }
        d.inverse[static_cast<size_t>(k)] = llt.solve(Eigen::Matrix3d::Identity());
        if (!d.inverse[static_cast<size_t>(k)].allFinite()) {
            error = "3x3 diagonal block of vertex " + std::to_string(k) + " has a non-finite inverse";
            return false;
        }
    }
    return true;
}

/// D3^-1 as a sparse matrix (for B = J D3^-1 J' and J D3^-1).
SpMat block_inverse_matrix(const BlockDiagonal& d)
{
    std::vector<Triplet> t;
    t.reserve(static_cast<size_t>(9 * d.blocks()));
    for (Eigen::Index k = 0; k < d.blocks(); ++k) {
        const int s = d.size(k);
        for (int a = 0; a < s; ++a)
            for (int b = 0; b < s; ++b)
                t.emplace_back(static_cast<int>(d.begin(k) + a), static_cast<int>(d.begin(k) + b),
                               d.inverse[static_cast<size_t>(k)](a, b));
    }
    SpMat m(d.n, d.n);
    m.setFromTriplets(t.begin(), t.end());
    return m;
}

/// One ascending block Gauss-Seidel sweep on A x = f (in place). Costs one pass over A.
void block_gauss_seidel_sweep(const SpMat& A, const BlockDiagonal& d, const Vec& f, Vec& x)
{
    for (Eigen::Index k = 0; k < d.blocks(); ++k) {
        const Eigen::Index i0 = d.begin(k);
        const int s = d.size(k);
        Eigen::Vector3d r = Eigen::Vector3d::Zero(), xold = Eigen::Vector3d::Zero();
        for (int a = 0; a < s; ++a) xold[a] = x[i0 + a];
        for (int a = 0; a < s; ++a) {
            double row = 0.0;
            for (SpMat::InnerIterator it(A, i0 + a); it; ++it) row += it.value() * x[it.col()];
            r[a] = f[i0 + a] - row;
        }
        // r = f - A x (with the old block); add back the block's own term: f - sum_{j not in k} A_kj x_j.
        r += d.block[static_cast<size_t>(k)] * xold;
        const Eigen::Vector3d xnew = d.inverse[static_cast<size_t>(k)] * r;
        for (int a = 0; a < s; ++a) x[i0 + a] = xnew[a];
    }
}

/// (D3 x) for the anticipation (L + U) x = A x - D3 x.
Vec block_times(const BlockDiagonal& d, const Vec& x)
{
    Vec out(x.size());
    for (Eigen::Index k = 0; k < d.blocks(); ++k) {
        const Eigen::Index i0 = d.begin(k);
        const int s = d.size(k);
        Eigen::Vector3d v = Eigen::Vector3d::Zero();
        for (int a = 0; a < s; ++a) v[a] = x[i0 + a];
        const Eigen::Vector3d w = d.block[static_cast<size_t>(k)] * v;
        for (int a = 0; a < s; ++a) out[i0 + a] = w[a];
    }
    return out;
}

}  // namespace

SolverResult IcaSolver::solve(const QpView& qp, const SolveContext& context)
{
    const IcaSettings& s = m_settings;
    SolverResult result;
    Counters& counters = result.counters;
    SolveLoop loop("ica", qp, s.common, context);

    const Eigen::Index m = qp.m();
    result.info["start"] = s.start;
    result.x = qp.x0;
    result.lambda = Vec::Zero(m);

    BlockDiagonal d;
    std::string error;
    if (!build_block_diagonal(qp.A, d, error))
        return loop.finish(result, SolveStatus::INVALID_INPUT, "ica: A must be SPD: " + error);
    const SpMat Dinv = block_inverse_matrix(d);
    const SpMat JD = qp.J * Dinv;                           // J D3^-1, m x n
    const SpMat B = SpMat(JD * qp.J.transpose()).pruned();  // J D3^-1 J', m x m
    Vec B_diag = Vec::Zero(m);
    for (Eigen::Index i = 0; i < m; ++i) B_diag[i] = B.coeff(i, i);
    long zero_rows = 0;
    for (Eigen::Index i = 0; i < m; ++i)
        if (!(B_diag[i] > 0.0)) ++zero_rows;
    result.info["B_nnz"] = static_cast<long>(B.nonZeros());
    result.info["B_diagonal"] = B.nonZeros() == static_cast<Eigen::Index>(m - zero_rows);
    result.info["zero_rows"] = zero_rows;

    Vec x = qp.x0;
    if (s.start == "unconstrained") {
        const double start_begin_s = loop.elapsed_s();
        Eigen::CholmodSupernodalLLT<SpMatCol, Eigen::Lower> llt;
        const SpMatCol A_col = qp.A;
        llt.compute(A_col);
        ++counters.cholmod_analyses;
        ++counters.cholmod_factorizations;
        counters.work_flops += cholmod_factor_flops(llt.cholmod());
        if (llt.info() != Eigen::Success)
            return loop.finish(result, SolveStatus::INVALID_INPUT,
                               "ica: start=unconstrained: CHOLMOD could not factor A (not SPD?)");
        x = llt.solve(qp.b);
        ++counters.cholmod_solves;
        counters.work_flops += cholmod_solve_flops(llt.cholmod());
        result.info["start_solve_s"] = loop.elapsed_s() - start_begin_s;
        result.info["start_solver"] = "cholmod";
    }
    loop.setup_phase("blocks_and_start");  // D3^-1, J D3^-1 J' and the start
    AOperator a_op(qp);  // the product with A: 3x3 blocks when A has them, built in the setup
    a_op.prepare(s.common.a_format, static_cast<int>(s.common.threads));
    loop.setup_phase("a_prepare");
    result.info["a_format"] = to_string(a_op.format());  // the storage the products read
    Vec lambda = Vec::Zero(m);
    if (context.lambda0 && context.lambda0->size() == m) lambda = context.lambda0->cwiseMax(0.0);
    const AccuracyScale scale = accuracy_scale(qp);  // setup, as in every solver
    counters.a_products += scale.a_products;
    loop.setup_phase("measure_scale");
    if (!loop.end_setup()) return loop.finish(result, SolveStatus::TIME_LIMIT);
    Vec Ax = a_product(a_op, x);
    ++counters.a_products;
    Vec f = qp.b + qp.J.transpose() * lambda;
    double native = (Ax - f).norm();
    Vec g = Ax - qp.b;

    auto finish = [&](SolveStatus status) {
        result.x = x;
        result.lambda = lambda;
        result.native_residual = native;
        result.info["native_residual_definition"] = "||A x - b - J' lambda||_2 (absolute)";
        std::ostringstream detail;  // the loop writes the reason
        detail << "native residual ||Ax-b-J'lambda||_2 = " << native << " (stationarity only)";
        return loop.finish(result, status, detail.str());
    };
    auto accuracy_error = [&] { return accuracy_from_gradient(qp, scale, x, g, lambda).max(); };

    if (!loop.notify({0, StepKind::START, &x, &lambda, native, -1, &counters, 0.0}))
        return finish(SolveStatus::STOPPED_BY_MONITOR);

    Vec q(m);
    double last_dlambda = 0.0;
    long last_sweeps = 0;
    for (;;) {
        // The loop's exit checks: non-finite, the stop rule, the iteration cap, the time.
        const SolveStatus exit = loop.check(
            counters.iterations, x.allFinite() && lambda.allFinite() && std::isfinite(native), native, accuracy_error);
        if (exit == SolveStatus::CONVERGED && counters.iterations > 0) {
            result.info["last_pgs_sweeps"] = last_sweeps;
            result.info["last_pgs_dlambda"] = last_dlambda;
        }
        if (exit != SolveStatus::NOT_RUN) return finish(exit);

        // 1. anticipation: the LCP of the block-Jacobi prediction x~ = D3^-1 (b + J'l - (L+U) x).
        if (m > 0) {
            const Vec LUx = Ax - block_times(d, x);
            q = qp.c + JD * (LUx - qp.b);
        }
        // 2. projected Gauss-Seidel on B lambda >= q, warm-started from the previous lambda.
        last_sweeps = 0;
        for (long sweep = 0; sweep < s.pgs_sweeps && m > 0; ++sweep) {
            double dl2 = 0.0;
            for (Eigen::Index i = 0; i < m; ++i) {
                if (!(B_diag[i] > 0.0)) {  // zero row of J: no force can act through it
                    dl2 += lambda[i] * lambda[i];
                    lambda[i] = 0.0;
                    continue;
                }
                double r = -q[i];
                for (SpMat::InnerIterator it(B, i); it; ++it) r += it.value() * lambda[it.col()];
                const double li = std::max(0.0, lambda[i] - r / B_diag[i]);
                dl2 += (li - lambda[i]) * (li - lambda[i]);
                lambda[i] = li;
            }
            ++last_sweeps;
            ++counters.pgs_sweeps;
            counters.work_flops += sparse_product_flops(static_cast<double>(B.nonZeros()));
            ++counters.lcp_iterations;
            last_dlambda = std::sqrt(dl2);
            if (last_dlambda <= s.pgs_tol) break;
            if (loop.time_up()) break;  // the outer loop reports the limit after this iteration
        }
        // 3. one block Gauss-Seidel sweep on A x = b + J' lambda.
        f = qp.b + qp.J.transpose() * lambda;
        block_gauss_seidel_sweep(qp.A, d, f, x);
        ++counters.a_products;
        // 4. the native residual (its A x is reused by the next anticipation).
        a_product(a_op, x, Ax);
        ++counters.a_products;
        g = Ax - qp.b;
        native = (Ax - f).norm();
        ++counters.iterations;

        if (!loop.notify({counters.iterations, StepKind::OUTER, &x, &lambda, native, -1, &counters, 0.0}))
            return finish(SolveStatus::STOPPED_BY_MONITOR);
    }
}

SolverEntry ica_entry()
{
    return solver_entry<IcaSolver>(
        "ica", ica_settings_table(),
        "iterative constraint anticipation (Otaduy et al. 2009) with PGS on J D3^-1 J', as the authors ran it",
        "any J");
}

}  // namespace cb
