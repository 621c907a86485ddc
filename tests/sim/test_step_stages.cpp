// The simulator's stages per step (detection, assembly, snapshot writing, solve): steps.csv has
// their times and peaks, the figures are finite and non-negative where the stage ran, and a
// stage's peak is its own (the high-water mark is reset at each stage's start).
#include "harness/sim_step_solver.hpp"
#include "sim/simulator.hpp"

#include <gtest/gtest.h>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

using namespace cb;
using namespace cb::sim;
using nlohmann::json;

namespace {

std::string stages_tmp_dir(const std::string& name)
{
    const char* dir = std::getenv("TMPDIR");
    std::string p = std::string(dir ? dir : "/tmp") + "/cb_test_stages_" + std::to_string(::getpid()) + "_" + name;
    ::mkdir(p.c_str(), 0755);
    return p;
}

/// A box resting on a plane: plane rows at every step, so detection has work.
json resting_box(int newton_iterations)
{
    return {{"name", "stages"},
            {"h", 0.01},
            {"frames", 3},
            {"newton_iterations", newton_iterations},
            {"a_M", 0.02},
            {"a_K", 0.01},
            {"solver", "mprgp"},
            {"detection", {{"margin", 0.005}}},
            {"bodies",
             {{{"box", {{"cells", {3, 3, 3}}, {"size", {0.3, 0.3, 0.3}}}},
               {"material", {{"youngs", 1e5}, {"poisson", 0.4}, {"density", 1000}}},
               {"translate", {0, 0.15, 0}}}}},
            {"obstacles", {{{"type", "plane"}, {"normal", {0, 1, 0}}, {"point", {0, 0, 0}}}}}};
}

/// steps.csv as one map column -> cell per row.
std::vector<std::map<std::string, std::string>> read_steps(const std::string& path)
{
    std::ifstream in(path);
    std::string line;
    std::getline(in, line);
    std::vector<std::string> header;
    std::stringstream hs(line);
    for (std::string cell; std::getline(hs, cell, ',');) header.push_back(cell);
    std::vector<std::map<std::string, std::string>> rows;
    while (std::getline(in, line)) {
        std::map<std::string, std::string> row;
        std::stringstream ls(line);
        size_t k = 0;
        for (std::string cell; std::getline(ls, cell, ','); ++k)
            if (k < header.size()) row[header[k]] = cell;
        EXPECT_EQ(k, header.size()) << line;
        rows.push_back(row);
    }
    return rows;
}

/// This process's resident size now (VmRSS, MiB).
double resident_mib()
{
    std::ifstream status("/proc/self/status");
    std::string line;
    while (std::getline(status, line))
        if (line.rfind("VmRSS:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
    return -1;
}

}  // namespace

TEST(StepStages, StepsCsvHasEveryStageFiniteAndNonNegative)
{
    SimulatorOptions opt;
    opt.solve_step = harness_step_solver();
    opt.out_dir = stages_tmp_dir("csv");
    Simulator sim(load_scene_json(resting_box(2), "stages.json", PathRoots{}), opt);
    ASSERT_TRUE(sim.run());
    const auto rows = read_steps(opt.out_dir + "/steps.csv");
    ASSERT_EQ(rows.size(), 6u);  // 3 frames, 2 Newton steps each
    const char* stage_columns[] = {"time_detection_s", "time_assembly_s",    "time_snapshot_s",
                                   "time_solve_s",     "time_solve_stage_s", "peak_detection_mb",
                                   "peak_assembly_mb", "peak_snapshot_mb",   "peak_solve_mb"};
    for (const auto& row : rows) {
        const bool first_newton = row.at("newton_iteration") == "0";
        EXPECT_GT(std::stol(row.at("rows")), 0);
        EXPECT_FALSE(row.at("snapshot").empty());
        for (const char* column : stage_columns) {
            ASSERT_TRUE(row.count(column)) << column;
            const double v = std::stod(row.at(column));
            EXPECT_TRUE(std::isfinite(v) && v >= 0) << column << " = " << v;
        }
        // Every stage that ran has a peak; detection runs on the first Newton step only.
        EXPECT_GT(std::stod(row.at("peak_assembly_mb")), 1.0);
        EXPECT_GT(std::stod(row.at("peak_snapshot_mb")), 1.0);
        EXPECT_GT(std::stod(row.at("peak_solve_mb")), 1.0);
        EXPECT_GT(std::stod(row.at("time_snapshot_s")), 0.0);
        EXPECT_GE(std::stod(row.at("time_solve_stage_s")), std::stod(row.at("time_solve_s")));
        if (first_newton)
            EXPECT_GT(std::stod(row.at("peak_detection_mb")), 1.0);
        else
            EXPECT_EQ(std::stod(row.at("peak_detection_mb")), 0.0);
    }
    std::ifstream record(opt.out_dir + "/simulation.json");
    EXPECT_EQ(json::parse(record).at("stage_peak_reset"), true);
    std::filesystem::remove_all(opt.out_dir);
}

TEST(StepStages, AStagePeakIsItsOwn)
{
    // The solve stage touches 64 MiB and frees it: its peak holds the block on top of the resident
    // size before it, and the next step's stages, measured after a reset, do not.
    // mmap, not malloc: malloc may serve the block from memory it keeps after a free (not returned
    // to the kernel), and the test is about the kernel's count, not the allocator's.
    constexpr size_t BLOCK_BYTES = size_t(64) << 20;
    std::vector<double> rss_before, rss_with_block;
    SimulatorOptions opt;
    opt.solve_step = [&](const StepSolveRequest& request) {
        rss_before.push_back(resident_mib());
        void* block = ::mmap(nullptr, BLOCK_BYTES, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
        EXPECT_NE(block, MAP_FAILED);
        if (block != MAP_FAILED) std::memset(block, 1, BLOCK_BYTES);  // touched: resident
        rss_with_block.push_back(resident_mib());
        if (block != MAP_FAILED) ::munmap(block, BLOCK_BYTES);
        StepSolveOutcome out;
        out.x = request.qp->x0;
        out.status = out.solver_status = "converged";
        return out;
    };
    Simulator sim(load_scene_json(resting_box(1), "stages.json", PathRoots{}), opt);
    std::vector<StepRecord> steps;
    steps.reserve(3);
    for (int s = 0; s < 3; ++s) steps.push_back(sim.step().at(0));
    ASSERT_EQ(rss_before.size(), 3u);
    for (size_t s = 0; s < steps.size(); ++s) {
        SCOPED_TRACE("step " + std::to_string(s));
        EXPECT_GT(rss_with_block[s], rss_before[s] + 60);
        EXPECT_GE(steps[s].peak_solve_mb, rss_with_block[s] - 0.5);  // VmRSS and VmHWM count pages alike
        EXPECT_GE(steps[s].peak_solve_mb, rss_before[s] + 60);
        if (s > 0) {  // after the block was freed: the reset forgot it
            EXPECT_LT(steps[s].peak_detection_mb, steps[s - 1].peak_solve_mb - 32) << "no reset before detection";
            EXPECT_LT(steps[s].peak_assembly_mb, steps[s - 1].peak_solve_mb - 32) << "no reset before assembly";
        }
    }
}
