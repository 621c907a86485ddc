// The measure's setup at scale (issue 47) changed how BodyMotion and accuracy_scale compute, not what:
// these tests keep the plain algorithms they replaced (one pass per quantity, the union-find joining
// in the old direction, diag(A) by a scan of every entry) and want the same bits from the library on
// sparse QPs with several bodies, stored zeros, rows that are not whole vertex groups, uncompressed
// storage and a DOF count that is not a multiple of 3.
#include "solvers/measure/accuracy.hpp"
#include "solvers/measure/body_motion.hpp"

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <numeric>
#include <random>
#include <vector>

namespace body_motion_reference {

/// The bits of a double: equal bits mean the same value, sign of zero and NaN payload included.
std::uint64_t bits(double v)
{
    std::uint64_t u = 0;
    std::memcpy(&u, &v, sizeof u);
    return u;
}

using cb::QpView;
using cb::SpMat;
using cb::Vec;
using Mat6 = cb::BodyMotion::Mat6;
using Vec6 = cb::BodyMotion::Vec6;
using LongVec6 = std::array<long double, 6>;

/// The displacement BodyMotion measures, computed as before the setup work: a union-find pass, the
/// centroids, one long double pass for AV and the loads, a second pass over AV for V'AV.
class Reference {
public:
    Reference(const QpView& qp, double length)
    {
        const SpMat& A = qp.A;
        const Eigen::Index n = A.rows();
        spatial = n % 3 == 0;
        per_node = spatial ? 3 : 1;
        inv_length = 1.0 / length;
        const int nodes = static_cast<int>(n / per_node);
        std::vector<int> parent(static_cast<size_t>(nodes));
        std::iota(parent.begin(), parent.end(), 0);
        const auto find = [&](int v) {  // with path halving: the partition (all the labels read) is the same
            while (parent[static_cast<size_t>(v)] != v) {
                parent[static_cast<size_t>(v)] = parent[static_cast<size_t>(parent[static_cast<size_t>(v)])];
                v = parent[static_cast<size_t>(v)];
            }
            return v;
        };
        for (Eigen::Index r = 0; r < A.outerSize(); ++r)
            for (SpMat::InnerIterator it(A, r); it; ++it) {
                if (it.value() == 0.0) continue;
                const int a = find(static_cast<int>(r / per_node)), b = find(static_cast<int>(it.col() / per_node));
                if (a != b) parent[static_cast<size_t>(a)] = b;
            }
        std::vector<int> id(static_cast<size_t>(nodes), -1);
        body.resize(static_cast<size_t>(nodes));
        for (int v = 0; v < nodes; ++v) {
            int& root_id = id[static_cast<size_t>(find(v))];
            if (root_id < 0) root_id = bodies++;
            body[static_cast<size_t>(v)] = root_id;
        }
        if (spatial) {
            std::vector<Eigen::Vector3d> centroid(static_cast<size_t>(bodies), Eigen::Vector3d::Zero());
            std::vector<double> count(static_cast<size_t>(bodies), 0.0);
            for (int v = 0; v < nodes; ++v) {
                centroid[static_cast<size_t>(body[static_cast<size_t>(v)])] +=
                    qp.x0.segment<3>(3 * static_cast<Eigen::Index>(v));
                count[static_cast<size_t>(body[static_cast<size_t>(v)])] += 1.0;
            }
            for (size_t b = 0; b < centroid.size(); ++b) centroid[b] /= count[b];
            offset.resize(nodes, 3);
            for (int v = 0; v < nodes; ++v)
                offset.row(v) = (qp.x0.segment<3>(3 * static_cast<Eigen::Index>(v)) -
                                 centroid[static_cast<size_t>(body[static_cast<size_t>(v)])])
                                    .transpose();
        }
        x0 = qp.x0;
        av.setZero(n, 6);
        std::vector<LongVec6> load(static_cast<size_t>(bodies), LongVec6{});
        const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> d = offset * inv_length;
        int mode[3];
        double value[3];
        for (Eigen::Index p = 0; p < n; ++p) {
            LongVec6 s{};
            long double r0 = -static_cast<long double>(qp.b[p]);
            for (SpMat::InnerIterator it(A, p); it; ++it) {
                if (it.value() == 0.0) continue;
                const long double a = it.value();
                r0 += a * x0[it.col()];
                if (!spatial) {
                    s[0] += a;
                    continue;
                }
                const int c = static_cast<int>(it.col()), v = c / 3;
                switch (c % 3) {
                case 0:
                    s[0] += a, s[4] += a * d(v, 2), s[5] += a * -d(v, 1);
                    break;
                case 1:
                    s[1] += a, s[5] += a * d(v, 0), s[3] += a * -d(v, 2);
                    break;
                default:
                    s[2] += a, s[3] += a * d(v, 1), s[4] += a * -d(v, 0);
                    break;
                }
            }
            for (int k = 0; k < 6; ++k) av(p, k) = static_cast<double>(s[static_cast<size_t>(k)]);
            const int rn = mode_row(p, mode, value);
            for (int t = 0; t < rn; ++t) load[body_of(p)][static_cast<size_t>(mode[t])] += value[t] * r0;
        }
        load0.assign(static_cast<size_t>(bodies), Vec6::Zero());
        for (int b = 0; b < bodies; ++b)
            for (int k = 0; k < 6; ++k)
                load0[static_cast<size_t>(b)][k] =
                    static_cast<double>(load[static_cast<size_t>(b)][static_cast<size_t>(k)]);
        std::vector<Mat6> E(static_cast<size_t>(bodies), Mat6::Zero());
        for (Eigen::Index p = 0; p < n; ++p) {
            const int rn = mode_row(p, mode, value);
            for (int t = 0; t < rn; ++t) E[body_of(p)].row(mode[t]) += value[t] * av.row(p);
        }
        pinv.assign(static_cast<size_t>(bodies), Mat6::Zero());
        for (int b = 0; b < bodies; ++b) {
            const Mat6& Eb = E[static_cast<size_t>(b)];
            if (!spatial) {
                if (Eb(0, 0) > 0.0) pinv[static_cast<size_t>(b)](0, 0) = 1.0 / Eb(0, 0);
                continue;
            }
            const Eigen::SelfAdjointEigenSolver<Mat6> eig(0.5 * (Eb + Eb.transpose()));
            const double cutoff = 1e-12 * eig.eigenvalues().maxCoeff();
            Vec6 inv = Vec6::Zero();
            for (int k = 0; k < 6; ++k)
                if (eig.eigenvalues()[k] > cutoff && eig.eigenvalues()[k] > 0.0) inv[k] = 1.0 / eig.eigenvalues()[k];
            pinv[static_cast<size_t>(b)] = eig.eigenvectors() * inv.asDiagonal() * eig.eigenvectors().transpose();
        }
        // (JV)' lambda per body, row by row as BodyMotion::row_loads sums it.
        J = qp.J;
    }

    double displacement(const Vec& x, const Vec& lambda) const
    {
        std::vector<Vec6> load = load0;
        for (Eigen::Index p = 0; p < x.size(); ++p) load[body_of(p)] += av.row(p).transpose() * (x[p] - x0[p]);
        int mode[3];
        double value[3];
        for (Eigen::Index i = 0; i < J.rows(); ++i) {
            if (lambda[i] == 0.0) continue;
            std::vector<int> touched;
            std::vector<Vec6> jv;
            for (SpMat::InnerIterator it(J, i); it; ++it) {
                if (it.value() == 0.0) continue;
                const int b = body[static_cast<size_t>(it.col() / per_node)];
                size_t e = 0;
                while (e < touched.size() && touched[e] != b) ++e;
                if (e == touched.size()) touched.push_back(b), jv.push_back(Vec6::Zero());
                const int cn = mode_row(it.col(), mode, value);
                for (int t = 0; t < cn; ++t) jv[e][mode[t]] += it.value() * value[t];
            }
            for (size_t e = 0; e < touched.size(); ++e) load[static_cast<size_t>(touched[e])] -= lambda[i] * jv[e];
        }
        double widest = 0.0;
        for (size_t v = 0; v < body.size(); ++v) {
            const Vec6 y = pinv[static_cast<size_t>(body[v])] * load[static_cast<size_t>(body[v])];
            if (!spatial) {
                widest = std::max(widest, std::abs(y[0]));
                continue;
            }
            const Eigen::Vector3d u =
                y.head<3>() +
                y.tail<3>().cross(Eigen::Vector3d(offset.row(static_cast<Eigen::Index>(v)).transpose())) * inv_length;
            widest = std::max(widest, u.cwiseAbs().maxCoeff());
        }
        return widest;
    }

    int bodies = 0;

    // The reference's state, open to the tests like the rest of it.
    size_t body_of(Eigen::Index p) const { return static_cast<size_t>(body[static_cast<size_t>(p / per_node)]); }
    int mode_row(Eigen::Index p, int mode[3], double value[3]) const
    {
        mode[0] = spatial ? static_cast<int>(p % 3) : 0;
        value[0] = 1.0;
        if (!spatial) return 1;
        const int a = static_cast<int>(p % 3), k1 = (a + 1) % 3, k2 = (a + 2) % 3;
        mode[1] = 3 + k1;
        value[1] = offset(p / 3, k2) * inv_length;
        mode[2] = 3 + k2;
        value[2] = -offset(p / 3, k1) * inv_length;
        return 3;
    }

    bool spatial = false;
    int per_node = 1;
    double inv_length = 1.0;
    std::vector<int> body;
    Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> offset;
    Vec x0;
    Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::RowMajor> av;
    std::vector<Vec6> load0;
    std::vector<Mat6> pinv;
    SpMat J;
};

/// A sparse QP of `bodies` bodies of `vertices` vertices each (3 DOFs per vertex unless `dofs` says
/// otherwise): random symmetric 3x3 couplings between random vertex pairs of a body (a chain keeps
/// each body connected), a dominant diagonal, random contact rows touching one or two bodies.
/// `quirks` adds stored zeros (a whole block of them between two bodies, which joins nothing, and
/// single zeros inside blocks) and couplings held by one entry (rows that are not whole groups).
struct Built {
    SpMat A, J;
    Vec b, c, x0;
};

Built build(int bodies, int vertices, bool quirks, std::uint32_t seed, Eigen::Index dofs = -1)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const int nv = bodies * vertices;
    const Eigen::Index n = dofs >= 0 ? dofs : 3 * static_cast<Eigen::Index>(nv);
    std::vector<cb::Triplet> t;
    const auto pair = [&](Eigen::Index p, Eigen::Index q, double v) {
        if (p >= n || q >= n) return;
        t.emplace_back(static_cast<int>(p), static_cast<int>(q), v);
        if (p != q) t.emplace_back(static_cast<int>(q), static_cast<int>(p), v);
    };
    for (Eigen::Index p = 0; p < n; ++p) pair(p, p, 40.0 + 10.0 * u(rng));
    for (int b = 0; b < bodies; ++b)
        for (int v = 0; v < vertices; ++v) {
            const int i = b * vertices + v;
            const int partners[2] = {v + 1 < vertices ? i + 1 : -1, b * vertices + static_cast<int>(rng() % vertices)};
            for (int w : partners) {
                if (w < 0 || w == i) continue;
                for (int r = 0; r < 3; ++r)
                    for (int s = 0; s < 3; ++s) pair(3 * i + r, 3 * w + s, u(rng));
            }
        }
    if (quirks && bodies > 1) {
        for (int r = 0; r < 3; ++r)
            for (int s = 0; s < 3; ++s) pair(3 * 0 + r, 3 * (nv - 1) + s, 0.0);  // a block of stored zeros
        pair(3 * 1 + 1, 3 * 2 + 2, 0.0);                                         // a zero inside a coupled block
        pair(Eigen::Index{3} * 1, 3 * Eigen::Index{vertices - 1} + 2,
             0.5);  // a coupling held by one entry: rows not whole groups
    }
    Built out;
    out.A = SpMat(n, n);
    out.A.setFromTriplets(t.begin(), t.end());
    out.x0.resize(n);
    for (Eigen::Index p = 0; p < n; ++p) out.x0[p] = 3.0 * (p / 3 % vertices) + 0.1 * u(rng) + 5.0 * (p % 3);
    out.b = Vec::NullaryExpr(n, [&] { return u(rng); });
    const int m = 2 * bodies;
    std::vector<cb::Triplet> jt;
    for (int i = 0; i < m; ++i)
        for (int e = 0; e < 3; ++e) jt.emplace_back(i, static_cast<int>(rng() % n), u(rng));
    out.J = SpMat(m, n);
    out.J.setFromTriplets(jt.begin(), jt.end());
    out.c = Vec::Zero(m);
    return out;
}

/// The library's displacement and the reference's, bit for bit, at the start and at random points;
/// with A unknown and known to equal A' to the bit (build() makes it so: then the bodies are found
/// from the entries right of each row's node, the reference reads every entry).
void expect_same_bits(const Built& q, double length, bool known_symmetric)
{
    SCOPED_TRACE(known_symmetric ? "A known symmetric" : "A not known symmetric");
    ASSERT_TRUE(q.A.isApprox(SpMat(q.A.transpose()), 0.0));
    const QpView view{q.A, q.b, q.J, q.c, q.x0, nullptr, nullptr, known_symmetric};
    const cb::BodyMotion motion(view, length);
    const Reference reference(view, length);
    EXPECT_EQ(motion.bodies(), reference.bodies);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int trial = 0; trial < 6; ++trial) {
        const Vec x = trial == 0 ? q.x0 : Vec(q.x0 + 0.01 * Vec::NullaryExpr(q.x0.size(), [&] { return u(rng); }));
        const Vec lambda =
            trial < 2 ? Vec::Zero(q.J.rows()) : Vec(Vec::NullaryExpr(q.J.rows(), [&] { return u(rng); }));
        const double got = motion.displacement(x, lambda), want = reference.displacement(x, lambda);
        EXPECT_EQ(bits(got), bits(want)) << "trial " << trial << ": " << got << " against " << want;
        EXPECT_GT(want, 0.0);  // a point that moves the bodies: the comparison reads real sums
        // Scaled variables (x = u .* y, as mprgp-coupled's precond = scaled iterates): read through u.
        const Vec scale = Vec::NullaryExpr(q.x0.size(), [&] { return 1.5 + u(rng); });
        const Vec y = x.cwiseQuotient(scale);
        const double scaled = motion.displacement_scaled(scale, y, lambda);
        const double formed = reference.displacement(scale.cwiseProduct(y), lambda);
        EXPECT_EQ(bits(scaled), bits(formed)) << "trial " << trial << ": " << scaled << " against " << formed;
    }
}

void expect_same_bits(const Built& q, double length)
{
    for (const bool known_symmetric : {false, true}) expect_same_bits(q, length, known_symmetric);
}

}  // namespace body_motion_reference

using namespace body_motion_reference;

TEST(BodyMotionReference, SeveralBodiesEqualThePlainPassesToTheLastBit)
{
    expect_same_bits(build(3, 40, false, 11), 7.0);
}

TEST(BodyMotionReference, AnAvBeyondTheCachesIsPrefetchedToTheSameBits)
{
    // 62k vertices: AV is 186k x 6 doubles (8.9 MB), past the size from which the pass prefetches.
    const Built q = build(2, 31000, false, 14);
    ASSERT_GE(q.A.rows() * 6 * static_cast<Eigen::Index>(sizeof(double)), Eigen::Index{8} << 20);
    expect_same_bits(q, 9.0);
}

TEST(BodyMotionReference, BodiesOfEveryRunLengthEqualThePlainPasses)
{
    // The widest move is taken four vertices at a time and the rest one by one: bodies of 1 to 9
    // vertices put the widest vertex in every lane and in the remainder.
    for (int vertices = 1; vertices <= 9; ++vertices) {
        SCOPED_TRACE(vertices);
        expect_same_bits(build(5, vertices, false, 20 + static_cast<std::uint32_t>(vertices)), 2.0);
    }
}

TEST(BodyMotionReference, StoredZerosAndRowsThatAreNotWholeGroupsEqualThePlainPasses)
{
    const Built q = build(3, 30, true, 12);
    expect_same_bits(q, 4.0);
    // The block of stored zeros joins nothing: three bodies, as without it, whichever half is read.
    EXPECT_EQ(cb::BodyMotion(QpView{q.A, q.b, q.J, q.c, q.x0}, 4.0).bodies(), 3);
    EXPECT_EQ(cb::BodyMotion(QpView{q.A, q.b, q.J, q.c, q.x0, nullptr, nullptr, true}, 4.0).bodies(), 3);
}

TEST(BodyMotionReference, UncompressedStorageEqualsThePlainPasses)
{
    Built q = build(2, 25, true, 13);
    q.A.uncompress();
    ASSERT_FALSE(q.A.isCompressed());
    expect_same_bits(q, 5.0);
}

TEST(BodyMotionReference, OneModePerNodeWhenTheDofCountIsNotAMultipleOfThree)
{
    expect_same_bits(build(2, 20, true, 14, 3 * 40 - 2), 3.0);
}

// A point that is not finite, given or only once scaled (u .* y overflows), is infinitely far.
TEST(BodyMotionReference, ScaledPointsThatAreNotFiniteAreInfinitelyFar)
{
    const Built q = build(2, 20, true, 16);
    const cb::BodyMotion motion(QpView{q.A, q.b, q.J, q.c, q.x0}, 3.0);
    const Vec lambda = Vec::Zero(q.J.rows());
    const double inf = std::numeric_limits<double>::infinity();
    const Vec ones = Vec::Ones(q.x0.size());
    Vec y = q.x0;
    EXPECT_LT(motion.displacement_scaled(ones, y, lambda), inf);
    y[y.size() - 1] = std::numeric_limits<double>::quiet_NaN();
    EXPECT_EQ(motion.displacement_scaled(ones, y, lambda), inf);
    EXPECT_EQ(motion.displacement(y, lambda), inf);
    Vec big = ones;
    big[5] = 1e308;
    y = q.x0;
    y[5] = 1e10;
    EXPECT_EQ(motion.displacement_scaled(big, y, lambda), inf);
    EXPECT_EQ(motion.displacement_scaled(Vec::Ones(3), y, lambda), inf);  // u of another size
}

// diag(A) by a search per row gives the scan's bits, and so the measure's weights 1 / D_jj, also
// where a diagonal entry is a stored zero, negative or absent (those borrow the largest D).
TEST(AccuracyScaleReference, InverseDiagonalEqualsTheScanOfEveryEntry)
{
    Built q = build(2, 20, true, 15);
    q.A.coeffRef(4, 4) = 0.0;
    q.A.coeffRef(7, 7) = -3.0;
    q.A.prune([](Eigen::Index r, Eigen::Index c, double) { return !(r == 10 && c == 10); });
    const QpView view{q.A, q.b, q.J, q.c, q.x0};
    const cb::AccuracyScale scale = cb::accuracy_scale(view);
    Vec diag = Vec::Zero(q.A.rows());
    for (Eigen::Index r = 0; r < q.A.outerSize(); ++r)
        for (SpMat::InnerIterator it(q.A, r); it; ++it)
            if (it.col() == it.row()) diag[r] += it.value();
    const double largest = diag.maxCoeff();
    ASSERT_EQ(scale.inv_diag.size(), diag.size());
    for (Eigen::Index j = 0; j < diag.size(); ++j) {
        const double want = 1.0 / (diag[j] > 0.0 ? diag[j] : largest);
        EXPECT_EQ(bits(scale.inv_diag[j]), bits(want)) << "j = " << j;
    }
    EXPECT_EQ(scale.inv_diag[10], 1.0 / largest);
}

namespace body_motion_reference {

/// Every part of the measure at (x, lambda) with `scale`, as raw bits.
std::vector<double> parts_of(const QpView& qp, const cb::AccuracyScale& scale, const Vec& x, const Vec& lambda)
{
    const Vec g = qp.A * x - qp.b;
    const cb::AccuracyParts e = cb::accuracy_from_gradient(qp, scale, x, g, lambda);
    return {e.stationarity, e.primal, e.dual, e.complementarity, e.gap, e.max()};
}

}  // namespace body_motion_reference

// The harness measures a decoupled run on its kept rows with the problem's scale carried over
// (accuracy_scale_with_rows): the same bits as a scale built afresh for those rows, and a fresh
// build (with its A-products) where the scene size came from the fallbacks.
TEST(AccuracyScaleReference, RowsOfAnotherQpReuseTheScaleToTheLastBit)
{
    const Built q = build(3, 30, true, 16);
    std::vector<cb::Triplet> kept;
    for (int i = 0; i < q.J.rows(); i += 2)
        for (SpMat::InnerIterator it(q.J, i); it; ++it)
            kept.emplace_back(i / 2, static_cast<int>(it.col()), it.value());
    SpMat J2((q.J.rows() + 1) / 2, q.J.cols());
    J2.setFromTriplets(kept.begin(), kept.end());
    const Vec c2 = Vec::Zero(J2.rows());
    for (const bool point_start : {false, true}) {
        const Vec x0 = point_start ? Vec(Vec::Zero(q.x0.size())) : q.x0;
        const QpView original{q.A, q.b, q.J, q.c, x0};
        const QpView solved{q.A, q.b, J2, c2, x0};
        const cb::AccuracyScale shared = cb::accuracy_scale(original);
        const cb::AccuracyScale fresh = cb::accuracy_scale(solved);
        const cb::AccuracyScale reused = cb::accuracy_scale_with_rows(shared, solved);
        EXPECT_EQ(reused.length_source, fresh.length_source);
        EXPECT_EQ(reused.a_products, fresh.a_products);
        EXPECT_EQ(point_start, fresh.a_products > 0) << fresh.length_source;
        std::mt19937 rng(5);
        std::uniform_real_distribution<double> u(-1.0, 1.0);
        for (int trial = 0; trial < 4; ++trial) {
            const Vec x = x0 + 0.01 * Vec::NullaryExpr(x0.size(), [&] { return u(rng); });
            const Vec lambda = Vec::NullaryExpr(J2.rows(), [&] { return u(rng); });
            const std::vector<double> want = parts_of(solved, fresh, x, lambda),
                                      got = parts_of(solved, reused, x, lambda);
            for (size_t k = 0; k < want.size(); ++k)
                EXPECT_EQ(bits(got[k]), bits(want[k])) << "part " << k << ": " << got[k] << " against " << want[k];
            EXPECT_GT(want[0], 0.0);  // stationarity reads the rows' loads
        }
    }
}
