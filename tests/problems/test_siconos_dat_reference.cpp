// The .dat import against Siconos' own reader (frictionContact_new_from_filename of Siconos
// numerics 4.4, linked here only): on each real file of tests/data/siconos_dat, every entry of
// W, q and mu agrees to 1e-15 (relative to the largest |W_ij|, |q_i|). Siconos' reader is called
// on these trusted files only: it allocates from the declared counts unchecked.
#include "problems/siconos_dat.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#ifdef CB_HAVE_SICONOS
#include <FrictionContactProblem.h>
#include <NumericsMatrix.h>
#endif

namespace {

namespace fs = std::filesystem;

const fs::path DATA = fs::path(CB_TEST_DATA_DIR) / "siconos_dat";

TEST(SiconosDatReference, EveryEntryAgreesWithSiconosReader)
{
#ifndef CB_HAVE_SICONOS
    GTEST_SKIP() << "Siconos numerics is not installed (libsiconos-numerics-dev): no reference reader";
#else
    for (const char* name :
         {"Rover4396.dat", "NESpheres_10_1.dat", "Confeti-ex13-4contact-Fc3D-SBM.dat", "Capsules-i101-404.dat"}) {
        const std::string path = (DATA / name).string();
        const cb::FrictionLocal ours = cb::read_siconos_dat_friction(path);
        FrictionContactProblem* theirs = frictionContact_new_from_filename(path.c_str());
        ASSERT_NE(theirs, nullptr) << name;
        ASSERT_EQ(theirs->dimension, 3) << name;
        ASSERT_EQ(theirs->numberOfContacts, ours.contacts()) << name;
        ASSERT_EQ(theirs->M->size0, ours.W.rows()) << name;
        ASSERT_EQ(theirs->M->size1, ours.W.cols()) << name;
        const Eigen::MatrixXd W(ours.W);
        const int n = int(W.rows());
        double w_scale = 0.0, w_diff = 0.0, q_scale = 0.0, q_diff = 0.0, mu_diff = 0.0;
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j) {
                const double s = NM_get_value(theirs->M, i, j);
                w_scale = std::max(w_scale, std::abs(s));
                w_diff = std::max(w_diff, std::abs(s - W(i, j)));
            }
        for (int i = 0; i < n; ++i) {
            q_scale = std::max(q_scale, std::abs(theirs->q[i]));
            q_diff = std::max(q_diff, std::abs(theirs->q[i] - ours.q[i]));
        }
        for (int c = 0; c < theirs->numberOfContacts; ++c)
            mu_diff = std::max(mu_diff, std::abs(theirs->mu[c] - ours.mu[c]));
        EXPECT_GT(w_scale, 0.0) << name;
        EXPECT_LE(w_diff, 1e-15 * w_scale) << name;  // measured: 0 on all four (both read with strtod rounding)
        EXPECT_LE(q_diff, 1e-15 * q_scale) << name;
        EXPECT_LE(mu_diff, 1e-15) << name;
        frictionContactProblem_free(theirs);
    }
#endif
}

}  // namespace
