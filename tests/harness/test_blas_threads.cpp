// contactbench runs BLAS on one thread unless OPENBLAS_NUM_THREADS says otherwise
// (harness/blas_threads.hpp): the count the binary reports in its provenance.
#include "cli_test_util.hpp"
#include "harness/blas_threads.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdlib>
#include <string>
#include <thread>

namespace {

/// contactbench --version --json under `env_prefix`: {"blas", "blas_threads", ...}.
nlohmann::json version_json(const std::string& env_prefix, const std::filesystem::path& dir)
{
    const cb::test::Output o =
        cb::test::run_captured(env_prefix + " '" + cb::test::contactbench_binary() + "' --version --json", dir);
    EXPECT_EQ(o.status, 0) << o.err;
    return nlohmann::json::parse(o.out);
}

bool is_openblas(const nlohmann::json& v) { return v.value("blas", "").find("openblas") != std::string::npos; }

}  // namespace

TEST(BlasThreads, OneThreadWhenTheUserSetNone)
{
    const auto dir = cb::test::make_test_work_dir("blas_threads_unset");
    const nlohmann::json v = version_json("env -u OPENBLAS_NUM_THREADS -u OMP_NUM_THREADS", dir);
    // OpenBLAS alone would start one thread per core here.
    EXPECT_EQ(v.at("blas_threads").get<int>(), is_openblas(v) ? 1 : 0) << v.dump();
}

TEST(BlasThreads, TheUsersCountHolds)
{
    const auto dir = cb::test::make_test_work_dir("blas_threads_set");
    const nlohmann::json v = version_json("env OPENBLAS_NUM_THREADS=2", dir);
    if (!is_openblas(v)) GTEST_SKIP() << "the BLAS is not OpenBLAS: " << v.value("blas", "");
    const int cores = static_cast<int>(std::max(1U, std::thread::hardware_concurrency()));
    EXPECT_EQ(v.at("blas_threads").get<int>(), std::min(2, cores)) << v.dump();  // OpenBLAS caps at the cores
}

TEST(BlasThreads, ChildProcessesInheritOneThread)
{
    ::unsetenv("OPENBLAS_NUM_THREADS");
    cb::limit_blas_threads();
    const char* v = std::getenv("OPENBLAS_NUM_THREADS");
    ASSERT_NE(v, nullptr);
    EXPECT_STREQ(v, "1");
    ::setenv("OPENBLAS_NUM_THREADS", "3", 1);
    cb::limit_blas_threads();  // a value already set is the user's
    EXPECT_STREQ(std::getenv("OPENBLAS_NUM_THREADS"), "3");
    ::setenv("OPENBLAS_NUM_THREADS", "1", 1);
}
