#include "solvers/measure/body_motion.hpp"
#include "solvers/linalg/avx2_lanes.hpp"
#include "solvers/linalg/disjoint_sets.hpp"
#include "solvers/linalg/prefault.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <type_traits>

namespace cb {

namespace {

/// Eigenvalues below this fraction of a body's largest are modes the body cannot move.
constexpr double RANK_CUTOFF = 1e-12;

std::atomic<long> g_live_modes{0};
std::atomic<long> g_peak_live_modes{0};

/// max(widest, |u_v|_inf over `count` vertices), u_v = y_t + (y_w x d_v) / length: a rigid motion
/// y = (translation, rotation) of one body read at its vertices' offsets d (row-major, 3 a vertex).
/// The terms of Eigen's cross product and sum, in the same order, one vertex at a time.
double widest_rigid_move_scalar(const double* d, Eigen::Index count, const BodyMotion::Vec6& y, double inv_length,
                                double widest)
{
    for (Eigen::Index v = 0; v < count; ++v) {
        const Eigen::Vector3d dv(d[3 * v], d[3 * v + 1], d[3 * v + 2]);
        const Eigen::Vector3d u = y.head<3>() + y.tail<3>().cross(dv) * inv_length;
        widest = std::max(widest, u.cwiseAbs().maxCoeff());
    }
    return widest;
}

#if defined(__x86_64__) && defined(__GNUC__)
/// widest_rigid_move_scalar four vertices at a time: the same products, differences and sums per
/// coordinate (no fused multiply-add), so every |u| has the same bits, and their maximum is the
/// same in any order. The pass had waited on a chain of scalar maxima (docs/a_product.md).
__attribute__((target("avx2"))) double widest_rigid_move_avx2(const double* __restrict d, Eigen::Index count,
                                                              const BodyMotion::Vec6& y, double inv_length,
                                                              double widest)
{
    const __m256d tx = _mm256_set1_pd(y[0]), ty = _mm256_set1_pd(y[1]), tz = _mm256_set1_pd(y[2]);
    const __m256d wx = _mm256_set1_pd(y[3]), wy = _mm256_set1_pd(y[4]), wz = _mm256_set1_pd(y[5]);
    const __m256d il = _mm256_set1_pd(inv_length), sign = _mm256_set1_pd(-0.0);
    __m256d most = _mm256_setzero_pd();
    Eigen::Index v = 0;
    for (; v + 4 <= count; v += 4) {
        // Four vertices' x y z x | y z x y | z x y z, to one register per coordinate.
        const __m256d r0 = _mm256_loadu_pd(d + 3 * v), r1 = _mm256_loadu_pd(d + 3 * v + 4),
                      r2 = _mm256_loadu_pd(d + 3 * v + 8);
        const __m256d a = _mm256_blend_pd(r0, r1, 0b1100);       // x0 y0 x2 y2
        const __m256d b = _mm256_permute2f128_pd(r0, r2, 0x21);  // z0 x1 z2 x3
        const __m256d c = _mm256_blend_pd(r1, r2, 0b1100);       // y1 z1 y3 z3
        const __m256d dx = _mm256_shuffle_pd(a, b, 0b1010), dy = _mm256_shuffle_pd(a, c, 0b0101),
                      dz = _mm256_shuffle_pd(b, c, 0b1010);
        const __m256d cx = _mm256_sub_pd(_mm256_mul_pd(wy, dz), _mm256_mul_pd(wz, dy));
        const __m256d cy = _mm256_sub_pd(_mm256_mul_pd(wz, dx), _mm256_mul_pd(wx, dz));
        const __m256d cz = _mm256_sub_pd(_mm256_mul_pd(wx, dy), _mm256_mul_pd(wy, dx));
        // max(term, most): a NaN term keeps `most`, as std::max(widest, term) keeps widest.
        most = _mm256_max_pd(_mm256_andnot_pd(sign, _mm256_add_pd(tx, _mm256_mul_pd(cx, il))), most);
        most = _mm256_max_pd(_mm256_andnot_pd(sign, _mm256_add_pd(ty, _mm256_mul_pd(cy, il))), most);
        most = _mm256_max_pd(_mm256_andnot_pd(sign, _mm256_add_pd(tz, _mm256_mul_pd(cz, il))), most);
    }
    widest = std::max(widest, max_lane_clearing_upper(most));
    return widest_rigid_move_scalar(d + 3 * v, count - v, y, inv_length, widest);
}
#endif

double widest_rigid_move(const double* d, Eigen::Index count, const BodyMotion::Vec6& y, double inv_length,
                         double widest)
{
#if defined(__x86_64__) && defined(__GNUC__)
    static const bool avx2 = __builtin_cpu_supports("avx2");
    if (avx2) return widest_rigid_move_avx2(d, count, y, inv_length, widest);
#endif
    return widest_rigid_move_scalar(d, count, y, inv_length, widest);
}

/// On an AV beyond the caches its rows are asked for 128 DOFs (6 KB) ahead: the pass waited on their
/// loads (docs/a_product.md). A small AV skips the prefetch and its instructions. Neither changes a sum.
constexpr Eigen::Index AV_AHEAD = 128;
constexpr Eigen::Index AV_PREFETCH_MIN_BYTES = Eigen::Index{8} << 20;

/// One body's run of DOFs [first, last) in the measure's pass: x_p = u_p y_p, or y_p without u.
struct AvRun {
    const double* av;  ///< AV, row-major, MODES a DOF
    const double* u;
    const double* y;
    const double* x0;
    Eigen::Index first, last;
    Eigen::Index av_last;  ///< the last index of AV, which a prefetch does not pass
};

/// sum += AV_p' (x_p - x0_p) in DOF order over the run; false when some x_p is not finite.
template <bool SCALED, bool PREFETCH> bool add_av_run_as(const AvRun& r, BodyMotion::Vec6& sum)
{
    bool finite = true;
    BodyMotion::Vec6 s = sum;  // a local: no store and reload of the sums per DOF
    for (Eigen::Index p = r.first; p < r.last; ++p) {
        if constexpr (PREFETCH)
            __builtin_prefetch(r.av + std::min<Eigen::Index>(BodyMotion::MODES * (p + AV_AHEAD), r.av_last));
        const double xp = SCALED ? r.u[p] * r.y[p] : r.y[p];
        finite = finite & std::isfinite(xp);
        s += Eigen::Map<const BodyMotion::Vec6>(r.av + BodyMotion::MODES * p) * (xp - r.x0[p]);
    }
    sum = s;
    return finite;
}

bool add_av_run(const AvRun& r, bool prefetch, BodyMotion::Vec6& sum)
{
    if (r.u) return prefetch ? add_av_run_as<true, true>(r, sum) : add_av_run_as<true, false>(r, sum);
    return prefetch ? add_av_run_as<false, true>(r, sum) : add_av_run_as<false, false>(r, sum);
}

}  // namespace

BodyMotion::Bodies::Gauge::Gauge()
{
    const long now = ++g_live_modes;
    long seen = g_peak_live_modes.load();
    while (now > seen && !g_peak_live_modes.compare_exchange_weak(seen, now)) {}
}

BodyMotion::Bodies::Gauge::~Gauge() { --g_live_modes; }

long BodyMotion::live_modes() { return g_live_modes.load(); }
long BodyMotion::peak_live_modes() { return g_peak_live_modes.load(); }
void BodyMotion::reset_peak_live_modes() { g_peak_live_modes = g_live_modes.load(); }

int BodyMotion::mode_row(Eigen::Index p, int mode[3], double value[3]) const
{
    mode[0] = m_spatial ? static_cast<int>(p % 3) : 0;
    value[0] = 1.0;
    if (!m_spatial) return 1;
    // (e_k x d)_a for the two axes k != a: +d_{a+2} for k = a+1 and -d_{a+1} for k = a+2 (mod 3).
    const int a = static_cast<int>(p % 3), k1 = (a + 1) % 3, k2 = (a + 2) % 3;
    const auto d = m_bodies->offset.row(p / 3);
    mode[1] = 3 + k1;
    value[1] = d[k2] * m_inv_length;
    mode[2] = 3 + k2;
    value[2] = -d[k1] * m_inv_length;
    return 3;
}

long double BodyMotion::spatial_row_sums(const SpMat& A, Eigen::Index p, const double* scaled_offset, long double r0,
                                         LongVec6& av) const
{
    // mode_row() unrolled by the column's axis, with the sums in named locals rather than an
    // indexed array (which kept every long double in memory): each sum still takes its terms in
    // column order, so the values are the same to the last bit. a * (-d) is subtracted as a * d:
    // rounding is symmetric in sign, and the negation no longer goes through the stack.
    const int* inner = A.innerIndexPtr();
    const double* val = A.valuePtr();
    const double* x0 = m_bodies->x0.data();
    const double* d = scaled_offset;
    const int first = A.outerIndexPtr()[p];
    const int last = A.isCompressed() ? A.outerIndexPtr()[p + 1] : first + A.innerNonZeroPtr()[p];
    long double t0 = 0.0L, t1 = 0.0L, t2 = 0.0L, q3 = 0.0L, q4 = 0.0L, q5 = 0.0L;
    for (int k = first; k < last; ++k) {
        if (val[k] == 0.0) continue;
        const long double a = val[k];
        const int c = inner[k], v = c / 3;
        const double* dv = d + 3 * static_cast<std::ptrdiff_t>(v);
        r0 += a * x0[c];
        switch (c - 3 * v) {
        case 0:
            t0 += a;
            q4 += a * dv[2];
            q5 -= a * dv[1];
            break;
        case 1:
            t1 += a;
            q5 += a * dv[0];
            q3 -= a * dv[2];
            break;
        default:
            t2 += a;
            q3 += a * dv[1];
            q4 -= a * dv[0];
            break;
        }
    }
    av = LongVec6{t0, t1, t2, q3, q4, q5};
    return r0;
}

namespace {

/// The connected components of A's node graph (node = DOF / per_node; stored zeros do not join),
/// numbered by their smallest node (DisjointSets' labels depend on the partition alone). A node's
/// rows mostly name the same neighbours: `joined` keeps each pair to one join. When A equals A' to
/// the bit, an entry right of a row's node meets every edge once (its mirror is the entry left of the
/// other node's rows, nonzero exactly when it is): the scan starts at the first column past the node,
/// found by a binary search (compressed rows' columns increase), and reads about half of A.
std::vector<int> node_bodies(const SpMat& A, int per_node, int nodes, bool a_symmetric, int& bodies)
{
    DisjointSets sets(nodes);
    std::vector<int> joined(static_cast<size_t>(nodes), -1);
    const bool upper_only = a_symmetric && A.isCompressed();
    const int* outer = A.outerIndexPtr();
    const int* inner = A.innerIndexPtr();
    const double* val = A.valuePtr();
    for (Eigen::Index r = 0; r < A.outerSize(); ++r) {
        const int node = static_cast<int>(per_node == 3 ? r / 3 : r);  // no division by a variable
        joined[static_cast<size_t>(node)] = node;
        const auto meet = [&](Eigen::Index col, double value) {
            const int other = static_cast<int>(per_node == 3 ? col / 3 : col);
            if (value == 0.0 || joined[static_cast<size_t>(other)] == node) return;  // a stored zero couples nothing
            sets.join(node, other);
            joined[static_cast<size_t>(other)] = node;
        };
        if (upper_only) {
            const int* end = inner + outer[r + 1];
            for (const int* k = std::lower_bound(inner + outer[r], end, per_node * (node + 1)); k != end; ++k)
                meet(*k, val[k - inner]);
        } else {
            for (SpMat::InnerIterator it(A, r); it; ++it) meet(it.col(), it.value());
        }
    }
    return sets.labels(bodies);
}

}  // namespace

BodyMotion::BodyMotion(const QpView& qp, double length)
{
    const SpMat& A = qp.A;
    const Eigen::Index n = A.rows();
    if (n == 0 || qp.x0.size() != n || qp.b.size() != n) return;
    m_spatial = n % 3 == 0;
    m_per_node = m_spatial ? 3 : 1;
    m_inv_length = length > 0.0 && std::isfinite(length) ? 1.0 / length : 1.0;
    const int nodes = static_cast<int>(n / m_per_node);
    const auto own = std::make_shared<Bodies>();
    m_bodies = own;  // mode_row() and spatial_row_sums() read it while it is filled
    Bodies& B = *own;

    int bodies = 0;
    B.body = node_bodies(A, m_per_node, nodes, qp.a_symmetric, bodies);
    auto body_of = [&](Eigen::Index p) { return static_cast<size_t>(B.body[static_cast<size_t>(p / m_per_node)]); };

    if (m_spatial) {
        std::vector<Eigen::Vector3d> centroid(static_cast<size_t>(bodies), Eigen::Vector3d::Zero());
        std::vector<double> count(static_cast<size_t>(bodies), 0.0);
        for (Eigen::Index v = 0; v < nodes; ++v) {
            centroid[body_of(3 * v)] += qp.x0.segment<3>(3 * v);
            count[body_of(3 * v)] += 1.0;
        }
        for (size_t b = 0; b < centroid.size(); ++b) centroid[b] /= count[b];
        B.offset.resize(nodes, 3);
        for (Eigen::Index v = 0; v < nodes; ++v)
            B.offset.row(v) = (qp.x0.segment<3>(3 * v) - centroid[body_of(3 * v)]).transpose();
    }
    B.x0 = qp.x0;

    // AV, V'(A x0 - b) and E = V'AV per body, one pass over A with long double sums (see the
    // header: the stiffness parts of a row cancel, and must do so before rounding to double).
    // E takes row p of AV right after it is rounded, in the order of p, as a separate pass would.
    B.av.resize(n, MODES);  // every row is written below
    // Faulted in with one call, not a fault a page (solvers/linalg/prefault.hpp).
    prefault_for_writing(B.av.data(), static_cast<size_t>(B.av.size()) * sizeof(double));
    std::vector<LongVec6> load(static_cast<size_t>(bodies), LongVec6{});
    std::vector<Mat6> E(static_cast<size_t>(bodies), Mat6::Zero());
    int mode[3];
    double value[3];
    const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> scaled_offset = B.offset * m_inv_length;
    for (Eigen::Index p = 0; p < A.outerSize(); ++p) {
        LongVec6 av{};
        long double r0 = -static_cast<long double>(qp.b[p]);
        if (m_spatial)
            r0 = spatial_row_sums(A, p, scaled_offset.data(), r0, av);
        else
            for (SpMat::InnerIterator it(A, p); it; ++it) {
                if (it.value() == 0.0) continue;
                r0 += static_cast<long double>(it.value()) * qp.x0[it.col()];
                av[0] += static_cast<long double>(it.value());
            }
        for (int k = 0; k < MODES; ++k) B.av(p, k) = static_cast<double>(av[static_cast<size_t>(k)]);
        const int rn = mode_row(p, mode, value);
        const size_t b = body_of(p);
        LongVec6& l = load[b];
        for (int s = 0; s < rn; ++s) l[static_cast<size_t>(mode[s])] += value[s] * r0;
        Mat6& Eb = E[b];
        for (int s = 0; s < rn; ++s) Eb.row(mode[s]) += value[s] * B.av.row(p);
    }
    B.load0.assign(static_cast<size_t>(bodies), Vec6::Zero());
    for (size_t b = 0; b < load.size(); ++b)
        for (int k = 0; k < MODES; ++k) B.load0[b][k] = static_cast<double>(load[b][static_cast<size_t>(k)]);

    B.pinv.assign(static_cast<size_t>(bodies), Mat6::Zero());
    for (size_t b = 0; b < E.size(); ++b) {
        if (!m_spatial) {
            if (E[b](0, 0) > 0.0 && std::isfinite(E[b](0, 0))) B.pinv[b](0, 0) = 1.0 / E[b](0, 0);
            continue;
        }
        if (!E[b].allFinite()) continue;  // not SPD: the Jacobi half of the measure still judges it
        const Eigen::SelfAdjointEigenSolver<Mat6> eig(0.5 * (E[b] + E[b].transpose()));
        const Vec6& lambda = eig.eigenvalues();
        const double cutoff = RANK_CUTOFF * lambda.maxCoeff();
        Vec6 inv = Vec6::Zero();
        for (int k = 0; k < MODES; ++k)
            if (lambda[k] > cutoff && lambda[k] > 0.0) inv[k] = 1.0 / lambda[k];
        B.pinv[b] = eig.eigenvectors() * inv.asDiagonal() * eig.eigenvectors().transpose();
    }

    m_rows = row_loads(qp.J);
    if (qp.friction && qp.friction->T.rows() == 2 * qp.J.rows() && qp.friction->T.cols() == n)
        m_tangents = row_loads(qp.friction->T);
}

BodyMotion BodyMotion::with_rows(const SpMat& J, const Friction* friction) const
{
    BodyMotion out = *this;
    if (!m_bodies) return out;  // the constructor stopped before the rows
    out.m_rows = row_loads(J);
    out.m_tangents = RowLoads{};
    if (friction && friction->T.rows() == 2 * J.rows() && friction->T.cols() == m_bodies->x0.size())
        out.m_tangents = row_loads(friction->T);
    return out;
}

BodyMotion::RowLoads BodyMotion::row_loads(const SpMat& rows) const
{
    RowLoads out;
    const Eigen::Index m = rows.rows(), n = m_bodies->x0.size();
    const std::vector<int>& body = m_bodies->body;
    int cmode[3];
    double cvalue[3];
    out.start.assign(static_cast<size_t>(m) + 1, 0);
    for (Eigen::Index i = 0; i < m; ++i) {
        const auto first = out.body.size();
        for (SpMat::InnerIterator it(rows, i); it; ++it) {
            if (it.value() == 0.0 || it.col() >= n) continue;
            const int b = body[static_cast<size_t>(it.col() / m_per_node)];
            size_t e = first;
            while (e < out.body.size() && out.body[e] != b) ++e;
            if (e == out.body.size()) {
                out.body.push_back(b);
                out.jv.push_back(Vec6::Zero());
            }
            const int cn = mode_row(it.col(), cmode, cvalue);
            for (int t = 0; t < cn; ++t) out.jv[e][cmode[t]] += it.value() * cvalue[t];
        }
        out.start[static_cast<size_t>(i) + 1] = static_cast<int>(out.body.size());
    }
    return out;
}

bool BodyMotion::subtract(const RowLoads& rows, const Vec& lambda, std::vector<Vec6>& load)
{
    const Eigen::Index m = rows.rows();
    if (lambda.size() != m || m <= 0) return true;
    if (!lambda.allFinite()) return false;
    for (Eigen::Index i = 0; i < m; ++i) {
        if (lambda[i] == 0.0) continue;
        for (int e = rows.start[static_cast<size_t>(i)]; e < rows.start[static_cast<size_t>(i) + 1]; ++e)
            load[static_cast<size_t>(rows.body[static_cast<size_t>(e)])] -= lambda[i] * rows.jv[static_cast<size_t>(e)];
    }
    return true;
}

double BodyMotion::displacement(const Vec& x, const Vec& lambda, const Vec& lambda_t) const
{
    return displacement_at(nullptr, x.data(), x.size(), lambda, lambda_t);
}

double BodyMotion::displacement_scaled(const Vec& u, const Vec& y, const Vec& lambda, const Vec& lambda_t) const
{
    if (u.size() != y.size()) return std::numeric_limits<double>::infinity();
    return displacement_at(u.data(), y.data(), y.size(), lambda, lambda_t);
}

double BodyMotion::displacement_at(const double* u, const double* y, Eigen::Index n, const Vec& lambda,
                                   const Vec& lambda_t) const
{
    if (!m_bodies) return 0.0;
    const Bodies& B = *m_bodies;
    const std::vector<int>& body = B.body;
    if (n != B.x0.size()) return std::numeric_limits<double>::infinity();
    std::vector<Vec6> load = B.load0;  // V'r per body
    // Run by run of one body's nodes (the bodies' nodes mostly come in runs), the run summed in a
    // local and stored when the body changes: the same terms added in the same order as straight
    // into load[b], so the same bits, without a store and a reload per DOF. Whether x is finite is
    // gathered on the way (a separate pass read x once more); the sums of a non-finite x are dropped.
    const auto nodes = static_cast<Eigen::Index>(body.size());
    bool finite = true;
    AvRun run{B.av.data(), u, y, B.x0.data(), 0, 0, B.av.size() - 1};
    const bool prefetch = B.av.size() * static_cast<Eigen::Index>(sizeof(double)) >= AV_PREFETCH_MIN_BYTES;
    Eigen::Index v = 0;
    while (v < nodes) {
        const int b = body[static_cast<size_t>(v)];
        Eigen::Index end = v + 1;
        while (end < nodes && body[static_cast<size_t>(end)] == b) ++end;
        run.first = v * m_per_node;
        run.last = end * m_per_node;
        finite = add_av_run(run, prefetch, load[static_cast<size_t>(b)]) && finite;
        v = end;
    }
    if (!finite) return std::numeric_limits<double>::infinity();
    if (!subtract(m_rows, lambda, load) || !subtract(m_tangents, lambda_t, load))
        return std::numeric_limits<double>::infinity();
    std::vector<Vec6> motion(load.size());
    for (size_t b = 0; b < load.size(); ++b) motion[b] = B.pinv[b] * load[b];
    double widest = 0.0;
    if (!m_spatial) {
        for (Eigen::Index v = 0; v < nodes; ++v)
            widest = std::max(widest, std::abs(motion[static_cast<size_t>(body[static_cast<size_t>(v)])][0]));
    } else {
        // Run by run of one body's vertices: the maximum is the same whatever the order it is taken in.
        Eigen::Index v = 0;
        while (v < nodes) {
            const int b = body[static_cast<size_t>(v)];
            Eigen::Index end = v + 1;
            while (end < nodes && body[static_cast<size_t>(end)] == b) ++end;
            widest = widest_rigid_move(B.offset.row(v).data(), end - v, motion[static_cast<size_t>(b)], m_inv_length,
                                       widest);
            v = end;
        }
    }
    return std::isfinite(widest) ? widest : std::numeric_limits<double>::infinity();
}

}  // namespace cb
