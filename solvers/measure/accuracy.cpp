#include "solvers/measure/accuracy.hpp"
#include "solvers/linalg/a_product.hpp"
#include "solvers/linalg/row_search.hpp"
#include "solvers/measure/accuracy_rows.hpp"

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <limits>
#include <vector>

namespace cb {

namespace {

constexpr double INF = std::numeric_limits<double>::infinity();
/// The unconstrained minimiser behind the length-scale fallback: Jacobi-PCG to this relative
/// residual (|D^-1 r|_inf), at most this many iterations (or n): a scale needs no more digits.
constexpr double UNCONSTRAINED_RTOL = 1e-3;
constexpr Eigen::Index UNCONSTRAINED_ITERATIONS = 200;

/// NaN must not read as "small": std::max with a NaN second argument would drop it.
double sanitize(double v) { return std::isfinite(v) ? v : INF; }

nlohmann::json finite_or_null(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }

/// Row r's entries in column r, summed from 0.0 (a scan of every entry gives the same bits).
/// A compressed row's columns increase (Eigen's invariant; the readers refuse other rows), so a
/// binary search finds them: a few cache lines per row instead of a pass over all of A.
Vec diagonal_sums(const SpMat& A)
{
    Vec diag(A.rows());
    const int* inner = A.innerIndexPtr();
    const double* val = A.valuePtr();
    const int* outer = A.outerIndexPtr();
    for (Eigen::Index r = 0; r < A.rows(); ++r) {
        const int first = outer[r];
        const int last = A.isCompressed() ? outer[r + 1] : first + A.innerNonZeroPtr()[r];
        if (A.isCompressed()) prefetch_diagonal_ahead(outer, val, r, A.rows());
        double d = 0.0;
        for (const int* k = std::lower_bound(inner + first, inner + last, static_cast<int>(r));
             k != inner + last && *k == r; ++k)
            d += val[k - inner];
        diag[r] = d;
    }
    return diag;
}

/// The rows' parts of the scale: 1 / n_i and n_i / k_i (k_i from s.inv_diag).
void row_scales(const QpView& qp, AccuracyScale& s)
{
    const Eigen::Index m = qp.m();
    s.inv_row_norm = Vec::Zero(m);
    s.length_per_multiplier = Vec::Zero(m);
    for (Eigen::Index i = 0; i < m; ++i) {
        double n2 = 0.0, k_n2 = 0.0;  // n_i^2 and n_i^2 k_i
        for (SpMat::InnerIterator it(qp.J, i); it; ++it) {
            n2 += it.value() * it.value();
            k_n2 += it.value() * it.value() / s.inv_diag[it.col()];
        }
        if (n2 > 0.0 && std::isfinite(n2)) {
            const double norm = std::sqrt(n2);
            s.inv_row_norm[i] = 1.0 / norm;
            s.length_per_multiplier[i] = norm * n2 / k_n2;  // n_i / k_i with k_i = k_n2 / n2
        }
    }
}

/// The scene size before its fallbacks: the view's fixed length (given, or the harness's reference
/// extent, fixed before any solver ran), else x0's extent (0 for a point-like start).
double first_length(const QpView& qp, std::string& source)
{
    if (qp.length != nullptr && qp.length->value > 0.0 && std::isfinite(qp.length->value)) {
        source = qp.length->source;
        return qp.length->value;
    }
    return point_extent(qp.x0, source);
}

}  // namespace

AccuracyScale accuracy_scale_with_rows(const AccuracyScale& shared, const QpView& qp)
{
    std::string source;
    const double l = first_length(qp, source);
    // The later fallbacks spend A-products (counted by the harness) or read the rows.
    const bool same_length = l > 0.0 && std::isfinite(l) && l == shared.length && source == shared.length_source;
    if (!same_length || shared.inv_diag.size() != qp.n() || shared.a_products != 0) return accuracy_scale(qp);
    AccuracyScale s = shared;
    row_scales(qp, s);
    s.bodies = shared.bodies.with_rows(qp.J, qp.friction);
    return s;
}

/// Largest axis extent of x read as 3-D points (n a multiple of 3), else the range of its entries.
double point_extent(const Vec& x, std::string& source)
{
    if (x.size() == 0) return 0.0;
    if (x.size() % 3 == 0) {
        source = "x0_extent";
        double widest = 0.0;
        for (int axis = 0; axis < 3; ++axis) {
            double lo = INF, hi = -INF;
            for (Eigen::Index k = axis; k < x.size(); k += 3) {
                lo = std::min(lo, x[k]);
                hi = std::max(hi, x[k]);
            }
            widest = std::max(widest, hi - lo);
        }
        return widest;
    }
    source = "x0_range";
    return x.maxCoeff() - x.minCoeff();
}

double AccuracyParts::max() const
{
    // friction is +0.0 without friction: max(e, +0.0) == e, bit for bit.
    return std::max(std::max(std::max(std::max(stationarity, primal), std::max(dual, complementarity)), gap), friction);
}

nlohmann::json AccuracyParts::to_json() const
{
    nlohmann::json out = {{"stationarity", finite_or_null(stationarity)},
                          {"primal", finite_or_null(primal)},
                          {"dual", finite_or_null(dual)},
                          {"complementarity", finite_or_null(complementarity)},
                          {"gap", finite_or_null(gap)},
                          {"max", finite_or_null(max())}};
    if (frictional) out["friction"] = finite_or_null(friction);
    return out;
}

nlohmann::json AccuracyScale::to_json() const
{
    return {{"length_scale", finite_or_null(length)},
            {"length_scale_source", length_source},
            {"stiffness_scale", finite_or_null(stiffness)}};
}

AccuracyScale accuracy_scale(const QpView& qp)
{
    AccuracyScale s;
    const Eigen::Index n = qp.n(), m = qp.m();
    // D = diag(A). A non-positive or non-finite diagonal (not SPD: the solvers refuse it) borrows
    // the largest one so that the measure stays defined.
    const Vec diag = diagonal_sums(qp.A);
    double d_max = 0.0, d_sum = 0.0;
    long d_count = 0;
    for (Eigen::Index j = 0; j < n; ++j)
        if (diag[j] > 0.0 && std::isfinite(diag[j])) {
            d_max = std::max(d_max, diag[j]);
            d_sum += diag[j];
            ++d_count;
        }
    if (d_max == 0.0) d_max = 1.0;
    s.inv_diag.resize(n);
    for (Eigen::Index j = 0; j < n; ++j)
        s.inv_diag[j] = 1.0 / (diag[j] > 0.0 && std::isfinite(diag[j]) ? diag[j] : d_max);
    s.stiffness = d_count > 0 ? d_sum / static_cast<double>(d_count) : 1.0;

    row_scales(qp, s);

    // The scene size: x0's extent is unchanged by a rigid move of the start and scales with the
    // length unit. A degenerate start (a point, e.g. x0 = 0) falls back on lengths of the
    // problem itself that share those invariances (docs/accuracy.md).
    std::string source;
    double l = first_length(qp, source);
    if (!(l > 0.0) || !std::isfinite(l)) {
        // Where the unconstrained problem would move a point-like start: the extent of its
        // minimiser, estimated by Jacobi-PCG from x0 (it follows x0 under every map (a)-(d)).
        // A length built from one Jacobi step, |D^-1 (b - A x0)|, underestimates it by up to
        // cond(A) (1e7 on the stress suite's random SPD cases).
        source = "unconstrained_extent";
        Vec x = qp.x0, r = qp.b - a_product(qp.A, qp.x0);
        ++s.a_products;
        const double r0 = r.cwiseProduct(s.inv_diag).lpNorm<Eigen::Infinity>();
        Vec z = r.cwiseProduct(s.inv_diag), p = z, Ap(n);
        double rz = r.dot(z);
        for (Eigen::Index k = 0; k < std::min<Eigen::Index>(n, UNCONSTRAINED_ITERATIONS) && r0 > 0.0; ++k) {
            Ap = a_product(qp.A, p);
            ++s.a_products;
            const double pap = p.dot(Ap);
            if (!(pap > 0.0) || !std::isfinite(pap)) break;
            const double alpha = rz / pap;
            x += alpha * p;
            r -= alpha * Ap;
            z = r.cwiseProduct(s.inv_diag);
            if (z.lpNorm<Eigen::Infinity>() <= UNCONSTRAINED_RTOL * r0) break;
            const double rz_next = r.dot(z);
            p = z + (rz_next / rz) * p;
            rz = rz_next;
        }
        std::string unused;
        l = point_extent(x, unused);
    }
    if ((!(l > 0.0) || !std::isfinite(l)) && m > 0) {
        source = "constraint_gap";
        l = 0.0;
        for (Eigen::Index i = 0; i < m; ++i) {
            if (s.inv_row_norm[i] == 0.0) continue;
            double jx = 0.0;
            for (SpMat::InnerIterator it(qp.J, i); it; ++it) jx += it.value() * qp.x0[it.col()];
            l = std::max(l, std::abs(qp.c[i] - jx) * s.inv_row_norm[i]);
        }
    }
    if (!(l > 0.0) || !std::isfinite(l)) {
        source = "unit";
        l = 1.0;
    }
    s.length = l;
    s.inv_length = 1.0 / l;
    s.inv_energy = 1.0 / (s.stiffness * l * l);
    s.length_source = source;
    s.bodies = BodyMotion(qp, l);
    return s;
}

double AccuracyScale::stationarity(const Vec& r, const Vec& x, const Vec& lambda) const
{
    return stationarity(r, x, lambda, Vec());
}

double AccuracyScale::stationarity(const Vec& r, const Vec& x, const Vec& lambda, const Vec& lambda_t) const
{
    double local = 0.0;
    for (Eigen::Index j = 0; j < r.size(); ++j) local = std::max(local, sanitize(std::abs(r[j]) * inv_diag[j]));
    return std::max(local * inv_length, body_motion(x, lambda, lambda_t));
}

double AccuracyScale::body_motion(const Vec& x, const Vec& lambda, const Vec& lambda_t) const
{
    return sanitize(bodies.displacement(x, lambda, lambda_t)) * inv_length;
}

double AccuracyScale::body_motion_scaled(const Vec& u, const Vec& y, const Vec& lambda) const
{
    return sanitize(bodies.displacement_scaled(u, y, lambda)) * inv_length;
}

AccuracyParts accuracy_from_gradient(const QpView& qp, const AccuracyScale& scale, const Vec& x, const Vec& g,
                                     const Vec& lambda, const Vec* lambda_t)
{
    AccuracyParts e;
    const Eigen::Index m = qp.m();
    const bool has_lambda = m > 0 && lambda.size() == m;
    // Friction fields of the right sizes (the reader guarantees them; a view built by hand may lack them).
    const Friction* f = qp.friction && qp.friction->mu.size() == m && m > 0 && qp.friction->T.rows() == 2 * m &&
                                qp.friction->T.cols() == qp.n()
                            ? qp.friction
                            : nullptr;
    const bool has_t = f && lambda_t && lambda_t->size() == 2 * m;
    const bool has_ct = f && f->cT.size() == 2 * m;
    Vec r = has_lambda ? Vec(g - qp.J.transpose() * lambda) : g;
    if (has_t) r -= f->T.transpose() * *lambda_t;
    RowParts rows;
    for (Eigen::Index i = 0; i < m; ++i) {
        double jx = 0.0;
        for (SpMat::InnerIterator it(qp.J, i); it; ++it) jx += it.value() * x[it.col()];
        const double slack = jx - qp.c[i];
        const double inv_norm = scale.inv_row_norm[i];
        if (inv_norm == 0.0) {
            rows.add_zero_row(qp.c[i]);
            continue;
        }
        rows.add_primal(slack, inv_norm);
        if (has_lambda) rows.add_multiplier(slack, lambda[i], inv_norm, scale.length_per_multiplier[i]);
        if (!f) continue;
        const double lt[2] = {has_t ? (*lambda_t)[2 * i] : 0.0, has_t ? (*lambda_t)[2 * i + 1] : 0.0};
        if (f->mu[i] == 0.0 && lt[0] == 0.0 && lt[1] == 0.0) continue;  // frictionless: nothing to add
        double tangent_slack[2];
        for (int k = 0; k < 2; ++k) {
            double tx = 0.0;
            for (SpMat::InnerIterator it(f->T, 2 * i + k); it; ++it) tx += it.value() * x[it.col()];
            tangent_slack[k] = tx - (has_ct ? f->cT[2 * i + k] : 0.0);
        }
        rows.add_friction(slack, has_lambda ? lambda[i] : 0.0, tangent_slack, lt, f->mu[i], inv_norm,
                          scale.length_per_multiplier[i]);
    }
    const RowParts parts = rows.scaled(scale.inv_length, scale.inv_energy);
    e.primal = parts.primal;
    e.dual = parts.dual;
    e.complementarity = parts.complementarity;
    e.gap = parts.gap;
    e.friction = parts.friction;
    e.frictional = f != nullptr;
    e.stationarity = scale.stationarity(r, x, has_lambda ? lambda : Vec(0), has_t ? *lambda_t : Vec());
    return e;
}

AccuracyParts accuracy(const QpView& qp, const AccuracyScale& scale, const Vec& x, const Vec& lambda,
                       const Vec* lambda_t)
{
    const Vec g = a_product(qp.A, x) - qp.b;
    return accuracy_from_gradient(qp, scale, x, g, lambda, lambda_t);
}

AccuracyParts accuracy(const QpView& qp, const Vec& x, const Vec& lambda, const Vec* lambda_t)
{
    return accuracy(qp, accuracy_scale(qp), x, lambda, lambda_t);
}

double energy_gap(const AccuracyScale& scale, double objective, double objective_star)
{
    if (!std::isfinite(objective) || !std::isfinite(objective_star)) return std::numeric_limits<double>::quiet_NaN();
    return std::abs(objective - objective_star) / (scale.stiffness * scale.length * scale.length);
}

double a_norm_distance(const QpView& qp, const AccuracyScale& scale, const Vec& x, const Vec& x_star)
{
    if (x.size() != qp.n() || x_star.size() != qp.n()) return std::numeric_limits<double>::quiet_NaN();
    const Vec d = x - x_star;
    const double energy = d.dot(a_product(qp.A, d));
    return std::sqrt(std::max(0.0, energy) / scale.stiffness) * scale.inv_length;
}

double max_violation(const QpView& qp, const Vec& x)
{
    if (qp.m() == 0) return 0.0;
    return std::max(0.0, (qp.c - qp.J * x).maxCoeff());
}

Vec fit_multipliers(const QpView& qp, const AccuracyScale& scale, const Vec& x, const Vec& g)
{
    const Eigen::Index m = qp.m();
    Vec lambda = Vec::Zero(m);
    if (m == 0) return lambda;
    const Vec slack = qp.J * x - qp.c;
    // Candidate rows: near-active (loose tolerance, because approximate iterates sit a little
    // off their face) or violated.
    std::vector<int> rows;
    for (Eigen::Index i = 0; i < m; ++i)
        if (scale.inv_row_norm[i] > 0.0 && slack[i] * scale.inv_row_norm[i] <= 1e-6 * scale.length)
            rows.push_back(static_cast<int>(i));
    for (int round = 0; round < 8 && !rows.empty(); ++round) {
        std::vector<Triplet> t;
        for (size_t r = 0; r < rows.size(); ++r)
            for (SpMat::InnerIterator it(qp.J, rows[r]); it; ++it)
                t.emplace_back(static_cast<int>(r), static_cast<int>(it.col()), it.value());
        SpMat JA(static_cast<Eigen::Index>(rows.size()), qp.n());
        JA.setFromTriplets(t.begin(), t.end());
        SpMatCol M = SpMatCol(JA * JA.transpose());
        double max_diag = 0.0;
        for (Eigen::Index i = 0; i < M.rows(); ++i) max_diag = std::max(max_diag, M.coeff(i, i));
        // Tikhonov term: keeps dependent (duplicated, parallel) rows solvable; the fit then
        // splits their multiplier, which leaves stationarity unchanged.
        SpMatCol reg(M.rows(), M.cols());
        reg.setIdentity();
        M += (1e-12 * std::max(max_diag, 1e-300)) * reg;
        Eigen::SimplicialLDLT<SpMatCol> ldlt(M);
        if (ldlt.info() != Eigen::Success) break;
        const Vec mu = ldlt.solve(Vec(JA * g));
        // Drop rows whose fitted multiplier is negative but that are not strictly active:
        // those are the ones the loose candidate tolerance let in.
        std::vector<int> keep;
        bool dropped = false;
        for (size_t r = 0; r < rows.size(); ++r) {
            if (mu[static_cast<Eigen::Index>(r)] < 0.0 &&
                slack[rows[r]] * scale.inv_row_norm[rows[r]] > 1e-9 * scale.length) {
                dropped = true;
                continue;
            }
            keep.push_back(rows[r]);
        }
        if (!dropped) {
            for (size_t r = 0; r < rows.size(); ++r) lambda[rows[r]] = mu[static_cast<Eigen::Index>(r)];
            return lambda;
        }
        rows.swap(keep);
    }
    return lambda;
}

}  // namespace cb
