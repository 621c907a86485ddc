// Real FCLIB files (written by Siconos and LMGC90; tests/data/fclib/NOTICE.md) taken as a
// user takes them: `contactbench convert FILE OUT.qpsnap --drop-friction` (each has mu != 0),
// then `contactbench solve` with two independent methods whose solutions must agree on
// F = 1/2 x'Ax - b'x to 1e-8. Global files (A = M, SPD): active-set (on the KKT system) and ipopt
// (interior point), which must also agree on x. Local files: A = W_NN is singular (more contacts
// than the bodies' degrees of freedom), so x is not unique and active-set (a Cholesky factor of A)
// refuses it; ipopt and mprgp-box (gradient projection with CG) agree on F, and the LCP's own
// residual |min(x, Ax - b)|_inf / |b|_inf of mprgp-box's x is checked here, outside the harness.
// Before issue 41 none of these files imported.
#include "problems/fclib_io.hpp"
#include "problems/qpsnap.hpp"
#include "solvers/core/registry.hpp"
#include "tests/harness/cli_test_util.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

namespace {

namespace fs = std::filesystem;
using cb::test::run_captured;

const fs::path FCLIB_DATA = fs::path(CB_TEST_DATA_DIR) / "fclib";

std::string quote(const fs::path& p) { return "'" + p.string() + "'"; }

/// A dense vector written by `solve --save-solution` (Matrix Market array format).
cb::Vec read_solution_mtx(const fs::path& path)
{
    std::ifstream in(path);
    std::string line;
    while (std::getline(in, line) && (line.empty() || line[0] == '%')) {}
    std::istringstream sizes(line);
    long rows = 0, cols = 0;
    sizes >> rows >> cols;
    cb::Vec v(rows);
    for (long i = 0; i < rows; ++i) in >> v[i];
    if (!in) ADD_FAILURE() << path << ": could not read " << rows << " values";
    return v;
}

double objective(const cb::Qp& qp, const cb::Vec& x) { return 0.5 * x.dot(qp.A * x) - qp.b.dot(x); }

struct RealFile {
    const char* name;
    const char* flags;  ///< convert's flags
    const char* kind;
    long n, m;
    const char* first;   ///< the solver whose x is checked
    const char* second;  ///< the independent one
};

void PrintTo(const RealFile& file, std::ostream* out) { *out << file.name; }

class FclibReal : public ::testing::TestWithParam<RealFile> {};

TEST_P(FclibReal, ImportsSolvesAndMatchesAnIndependentReference)
{
    if (cb::fclib_version().empty()) GTEST_SKIP() << "FCLIB import not built (libfclib-dev missing)";
    const auto names = cb::builtin_registry().names();
    if (std::find(names.begin(), names.end(), "ipopt") == names.end())
        GTEST_SKIP() << "the ipopt peer is not built: no independent reference";
    const RealFile& file = GetParam();
    const fs::path work = cb::test::make_test_work_dir(std::string("fclib_real_") + file.kind);
    const std::string bin = cb::test::contactbench_binary();
    const fs::path snap = work / "problem.qpsnap";

    // Without --drop-friction a local file is refused, naming its kind and the way out; a global one
    // keeps its friction (a version 2 snapshot: tests/problems/test_fclib_friction_global.cpp).
    const auto plain = run_captured(bin + " convert " + quote(FCLIB_DATA / file.name) + " " + quote(snap), work);
    if (std::string(file.kind) == "fclib_local") {
        EXPECT_EQ(plain.status, 2);
        EXPECT_NE(plain.err.find(std::string("this ") + file.kind + " problem has friction"), std::string::npos)
            << plain.err;
        EXPECT_NE(plain.err.find("--drop-friction"), std::string::npos) << plain.err;
        EXPECT_FALSE(fs::exists(snap));
    } else {
        EXPECT_EQ(plain.status, 0) << plain.err;
        EXPECT_NE(plain.out.find("kept friction"), std::string::npos) << plain.out;
        EXPECT_TRUE(cb::read_qpsnap(snap.string()).frictional());
    }

    const auto converted =
        run_captured(bin + " convert " + quote(FCLIB_DATA / file.name) + " " + quote(snap) + " " + file.flags, work);
    ASSERT_EQ(converted.status, 0) << converted.err;
    EXPECT_NE(converted.out.find("dropped friction"), std::string::npos) << converted.out;
    const cb::Qp qp = cb::read_qpsnap(snap.string());
    EXPECT_EQ(qp.n(), file.n);
    EXPECT_EQ(qp.m(), file.m);
    const nlohmann::json& provenance = qp.meta.at("provenance");
    EXPECT_EQ(provenance.at("format"), file.kind);
    EXPECT_EQ(provenance.at("file"), file.name);
    EXPECT_GT(provenance.at("dropped_friction").at("mu_max").get<double>(), 0.0);

    // `info` on the FCLIB file names it; `solve` on it says to convert.
    const auto info = run_captured(bin + " info " + quote(FCLIB_DATA / file.name), work);
    EXPECT_EQ(info.status, 0) << info.err;
    EXPECT_NE(info.out.find(std::string("an FCLIB ") + file.kind + " problem (HDF5)"), std::string::npos) << info.out;
    const auto direct = run_captured(bin + " solve " + quote(FCLIB_DATA / file.name) + " --solver active-set", work);
    EXPECT_EQ(direct.status, 2);
    EXPECT_NE(direct.err.find("convert it first: contactbench convert"), std::string::npos) << direct.err;

    std::map<std::string, cb::Vec> x;
    for (const std::string solver : {file.first, file.second}) {
        const fs::path out = work / solver;
        const auto run = run_captured(bin + " solve " + quote(snap) + " --solver " + solver +
                                          " --set tol=1e-10 --save-solution " + quote(out),
                                      work);
        ASSERT_EQ(run.status, 0) << solver << ": " << run.err << run.out;
        x[solver] = read_solution_mtx(out / "x.mtx");
        ASSERT_EQ(x[solver].size(), qp.n());
        std::printf("%s %s: F = %.17g, |x|_inf = %.6g\n", file.name, solver.c_str(), objective(qp, x[solver]),
                    x[solver].lpNorm<Eigen::Infinity>());
    }
    const cb::Vec& xa = x[file.first];
    const cb::Vec& xi = x[file.second];
    const double fa = objective(qp, xa), fi = objective(qp, xi);
    EXPECT_LE(std::abs(fa - fi), 1e-8 * std::abs(fa))
        << "F: " << file.first << " " << fa << ", " << file.second << " " << fi;
    if (std::string(file.kind) == "fclib_global") {  // A = M is SPD: one x
        EXPECT_LE((xa - xi).lpNorm<Eigen::Infinity>(), 1e-8 * std::max(1.0, xa.lpNorm<Eigen::Infinity>()))
            << "x differs by " << (xa - xi).lpNorm<Eigen::Infinity>();
    } else {  // J = I, c = 0: min(x, Ax - b) = 0 at a solution (measured 1.6e-10 and 8.9e-7)
        const cb::Vec r = xa.cwiseMin(qp.A * xa - qp.b);
        EXPECT_LE(r.lpNorm<Eigen::Infinity>() / qp.b.lpNorm<Eigen::Infinity>(), 1e-5);
    }
    fs::remove_all(work);
}

INSTANTIATE_TEST_SUITE_P(Siconos, FclibReal,
                         ::testing::Values(RealFile{"LMGC_GlobalFrictionContactProblem00046.hdf5", "--drop-friction",
                                                    "fclib_global", 162, 9, "active-set", "ipopt"},
                                           RealFile{"CubeH8.hdf5", "--drop-friction", "fclib_global", 162, 1,
                                                    "active-set", "ipopt"},
                                           RealFile{"Capsules-i125-1213.hdf5", "--drop-friction --symmetrise",
                                                    "fclib_local", 286, 286, "mprgp-box", "ipopt"},
                                           RealFile{"LMGC_100_PR_PerioBox-i00361-60-03000.hdf5", "--drop-friction",
                                                    "fclib_local", 60, 60, "mprgp-box", "ipopt"}),
                         [](const ::testing::TestParamInfo<RealFile>& info) {
                             std::string name = info.param.name;
                             name = name.substr(0, name.find('.'));
                             for (char& ch : name)
                                 if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
                             return name;
                         });

}  // namespace
