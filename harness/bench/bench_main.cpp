// main() of cb_bench (every harness/bench/*.cpp registers its benchmarks; none defines main).
#include <benchmark/benchmark.h>

#include <cstdio>

#ifndef CB_BUILD_TYPE
#define CB_BUILD_TYPE "unknown"
#endif

int main(int argc, char** argv)
{
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    // DESIGN.md: say it rather than hide it.
    std::fprintf(stderr,
                 "note: \"Library was built as DEBUG\" below refers to Debian's packaged Google Benchmark "
                 "library, not to contactbench (built as %s)\n",
                 CB_BUILD_TYPE);
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
