// Tests of the decoupling transform (ALGORITHMS.md §1).
#include "problems/synthetic.hpp"
#include "solvers/mprgp/decouple.hpp"

#include <gtest/gtest.h>

#include <set>

namespace {

cb::SpMat rows_matrix(int n, const std::vector<std::vector<std::pair<int, double>>>& rows)
{
    std::vector<cb::Triplet> t;
    for (size_t r = 0; r < rows.size(); ++r)
        for (auto [col, v] : rows[r]) t.emplace_back(static_cast<int>(r), col, v);
    cb::SpMat J(static_cast<Eigen::Index>(rows.size()), n);
    J.setFromTriplets(t.begin(), t.end());
    return J;
}

cb::Qp qp_with(const cb::SpMat& J)
{
    cb::Qp qp;
    const Eigen::Index n = J.cols();
    qp.A.resize(n, n);
    qp.A.setIdentity();
    qp.b = cb::Vec::Zero(n);
    qp.x0 = cb::Vec::Zero(n);
    qp.J = J;
    qp.c = cb::Vec::LinSpaced(J.rows(), 1.0, static_cast<double>(J.rows()));  // depth c_i - J_i x0 = c_i
    return qp;
}

TEST(Decouple, ColumnStructureDecidesDecoupled)
{
    // Rows 0 and 1 touch DOFs 0 and 2: the same vertex 0 -> coupled.
    EXPECT_FALSE(cb::is_decoupled(rows_matrix(9, {{{0, 1.0}}, {{2, 1.0}}})));
    // DOFs 2 and 3 are vertices 0 and 1 -> decoupled.
    EXPECT_TRUE(cb::is_decoupled(rows_matrix(9, {{{2, 1.0}}, {{3, 1.0}}})));
    EXPECT_TRUE(cb::is_decoupled(rows_matrix(9, {})));
    // Explicit zeros do not touch a vertex.
    EXPECT_TRUE(cb::is_decoupled(rows_matrix(9, {{{0, 1.0}, {3, 0.0}}, {{4, 1.0}}})));
}

TEST(Decouple, GreedyKeepsOneRowPerVertexInEachOrder)
{
    // Row 0: vertices {0,1}; row 1: {1}; row 2: {2}; row 3: {0, 2}; row 4: {3}.
    const cb::SpMat J =
        rows_matrix(12, {{{0, 1.0}, {3, 1.0}}, {{4, 1.0}}, {{6, 1.0}}, {{1, 1.0}, {8, 1.0}}, {{9, 1.0}}});
    cb::Qp qp = qp_with(J);
    // authors: kinds plane (rows 2, 4) first, then inter-body (rows 0, 1, 3), detection order.
    qp.contacts.kind = {2, 2, 0, 2, 0};
    const cb::DecoupleReport a = cb::decouple_rows(qp.view(), qp.contacts, cb::DecoupleOrder::AUTHORS, 0);
    EXPECT_EQ(a.kept_rows, (std::vector<int>{0, 2, 4}));
    EXPECT_FALSE(a.already_decoupled);
    EXPECT_EQ(a.rows_before, 5);
    EXPECT_EQ(a.rows_after, 3);
    // depth: c = 1..5, deepest first: rows 4, 3, 2(clash with 3), 1, 0(clash) -> {1, 3, 4}.
    const cb::DecoupleReport d = cb::decouple_rows(qp.view(), {}, cb::DecoupleOrder::DEPTH, 0);
    EXPECT_EQ(d.kept_rows, (std::vector<int>{1, 3, 4}));
    // random: seeded, reproducible, and always a decoupled maximal choice.
    const cb::DecoupleReport r1 = cb::decouple_rows(qp.view(), {}, cb::DecoupleOrder::RANDOM, 7);
    const cb::DecoupleReport r2 = cb::decouple_rows(qp.view(), {}, cb::DecoupleOrder::RANDOM, 7);
    EXPECT_EQ(r1.kept_rows, r2.kept_rows);
    EXPECT_EQ(r1.seed, 7u);
    std::set<std::vector<int>> choices;
    for (std::uint64_t seed = 0; seed < 40; ++seed) {
        const cb::DecoupleReport r = cb::decouple_rows(qp.view(), {}, cb::DecoupleOrder::RANDOM, seed);
        const cb::Qp sub = cb::select_rows(qp, r.kept_rows);
        EXPECT_TRUE(cb::is_decoupled(sub.J));
        EXPECT_TRUE(std::find(r.kept_rows.begin(), r.kept_rows.end(), 4) !=
                    r.kept_rows.end());  // row 4 clashes with none
        choices.insert(r.kept_rows);
    }
    EXPECT_GE(choices.size(), 2u);  // the seed matters
}

TEST(Decouple, AlreadyDecoupledPassesThroughUntouched)
{
    const cb::Qp qp = cb::make_synthetic("plane", {{"nx", 3}, {"ny", 2}, {"nz", 3}}, 1);
    ASSERT_TRUE(cb::is_decoupled(qp.J));
    const cb::DecoupleReport r = cb::decouple_rows(qp.view(), qp.contacts, cb::DecoupleOrder::RANDOM, 5);
    EXPECT_TRUE(r.already_decoupled);
    EXPECT_EQ(r.rows_after, r.rows_before);
    EXPECT_EQ(static_cast<Eigen::Index>(r.kept_rows.size()), qp.m());
}

TEST(Decouple, CoupledFamilyBecomesDecoupledAndMetadataFollows)
{
    const cb::Qp qp = cb::make_synthetic("coupled", {{"nx", 3}, {"ny", 2}, {"nz", 3}}, 2);
    ASSERT_FALSE(cb::is_decoupled(qp.J));
    for (cb::DecoupleOrder order : {cb::DecoupleOrder::AUTHORS, cb::DecoupleOrder::RANDOM, cb::DecoupleOrder::DEPTH}) {
        const cb::DecoupleReport r = cb::decouple_rows(qp.view(), qp.contacts, order, 3);
        ASSERT_GT(r.rows_after, 0);
        EXPECT_LT(r.rows_after, r.rows_before);
        const cb::Qp sub = cb::select_rows(qp, r.kept_rows);
        EXPECT_TRUE(cb::is_decoupled(sub.J));
        ASSERT_EQ(sub.m(), r.rows_after);
        for (size_t k = 0; k < r.kept_rows.size(); ++k) {
            const int i = r.kept_rows[k];
            EXPECT_EQ(sub.c[static_cast<Eigen::Index>(k)], qp.c[i]);
            EXPECT_EQ((sub.J.row(static_cast<Eigen::Index>(k)) - qp.J.row(i)).norm(), 0.0);
            if (!qp.contacts.kind.empty()) {
                EXPECT_EQ(sub.contacts.kind[k], qp.contacts.kind[static_cast<size_t>(i)]);
            }
        }
        // Maximal: every dropped row shares a vertex with a kept one.
        std::set<Eigen::Index> taken;
        for (int i : r.kept_rows)
            for (cb::SpMat::InnerIterator it(qp.J, i); it; ++it)
                if (it.value() != 0.0) taken.insert(it.col() / 3);
        for (Eigen::Index i = 0; i < qp.m(); ++i) {
            if (std::find(r.kept_rows.begin(), r.kept_rows.end(), static_cast<int>(i)) != r.kept_rows.end()) continue;
            bool clash = false;
            for (cb::SpMat::InnerIterator it(qp.J, i); it; ++it)
                if (it.value() != 0.0 && taken.count(it.col() / 3)) clash = true;
            EXPECT_TRUE(clash) << "row " << i;
        }
    }
}

TEST(Decouple, OrderNames)
{
    EXPECT_EQ(cb::decouple_order_from_string("depth"), cb::DecoupleOrder::DEPTH);
    EXPECT_STREQ(cb::to_string(cb::DecoupleOrder::AUTHORS), "authors");
    try {
        cb::decouple_order_from_string("sorted");
        FAIL();
    } catch (const cb::InputError& e) {
        EXPECT_NE(std::string(e.what()).find("authors, random, depth"), std::string::npos) << e.what();
    }
}

}  // namespace
