// How much of a snapshot the reader holds mapped (problems/qpsnap.cpp PageRelease): its checks
// walk the whole mapped file, then the copy into A gives A's pages back behind it, so that the
// file (760 MB at a million DOFs) never sits whole in memory beside the matrix built from it.
// Read through /proc/self/smaps, the mapping's own resident size: the pages in this process's
// page tables, which only the reader's own faults and releases change.
#include "problems/qpsnap.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <unistd.h>
#include <vector>

namespace cb {
namespace {

struct MappedPagesSeen {
    std::string pass;
    std::uint64_t rss_bytes = 0;
    std::uint64_t size = 0;
};

std::vector<MappedPagesSeen>& mapped_pages_seen()
{
    static std::vector<MappedPagesSeen> seen;
    return seen;
}

/// The Rss line of the /proc/self/smaps entry that starts at `start`; -1 when there is none.
long long mapped_pages_rss_bytes(const void* start)
{
    char head[32];
    std::snprintf(head, sizeof head, "%llx-", static_cast<unsigned long long>(reinterpret_cast<std::uintptr_t>(start)));
    std::ifstream smaps("/proc/self/smaps");
    std::string line;
    bool in_entry = false;
    while (std::getline(smaps, line)) {
        if (line.rfind(head, 0) == 0) {
            in_entry = true;
            continue;
        }
        if (in_entry && line.rfind("Rss:", 0) == 0) {
            std::istringstream fields(line.substr(4));
            long long kib = -1;
            fields >> kib;
            return kib * 1024;
        }
    }
    return -1;
}

void mapped_pages_observe(const char* pass, const unsigned char* mapping, std::uint64_t size)
{
    const long long rss = mapped_pages_rss_bytes(mapping);
    mapped_pages_seen().push_back({pass, rss < 0 ? ~0ULL : std::uint64_t(rss), size});
}

/// A banded SPD A (7 entries a row, diagonally dominant): n = 3 * 100000 gives a 41 MB file.
Qp mapped_pages_qp()
{
    const int n = 300000, half_band = 3, m = 50;
    Qp qp;
    qp.A.resize(n, n);
    qp.A.reserve(Eigen::VectorXi::Constant(n, 2 * half_band + 1));
    for (int i = 0; i < n; ++i)
        for (int j = std::max(0, i - half_band); j <= std::min(n - 1, i + half_band); ++j)
            qp.A.insert(i, j) = i == j ? 10.0 + 1e-3 * (i % 7) : -1.0 / (1 + std::abs(i - j));
    qp.A.makeCompressed();
    qp.b = Vec::LinSpaced(n, -1.0, 1.0);
    qp.x0 = Vec::LinSpaced(n, 0.0, 2.0);
    qp.J.resize(m, n);
    for (int r = 0; r < m; ++r) qp.J.insert(r, 3 * r + 1) = 1.0;
    qp.J.makeCompressed();
    qp.c = Vec::Zero(m);
    return qp;
}

TEST(QpsnapMappedPages, ReaderGivesTheFilePagesBackBehindEachPass)
{
    const auto dir = std::filesystem::temp_directory_path() / ("cb_test_mapped_pages_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    const std::string path = (dir / "banded.qpsnap").string();
    const Qp written = mapped_pages_qp();
    write_qpsnap(path, written);
    const std::uint64_t file_size = std::filesystem::file_size(path);
    ASSERT_GT(file_size, std::uint64_t(38) << 20);

    mapped_pages_seen().clear();
    set_qpsnap_pass_observer(&mapped_pages_observe);
    const Qp read = read_qpsnap(path);
    set_qpsnap_pass_observer(nullptr);

    // Every pass was seen. The checks walk the whole file (mapped whole and populated); the copy
    // into A gives A's arrays back (36 MB of the 41 MB file), so after it the mapping holds at
    // most the other arrays and 1 MB (shared edge pages, the kernel's fault-around). Before, it
    // held the whole file until the reader returned.
    const std::vector<std::string> passes = {"checksums", "structure", "values", "A built"};
    ASSERT_EQ(mapped_pages_seen().size(), passes.size());
    for (size_t k = 0; k < passes.size(); ++k) {
        EXPECT_EQ(mapped_pages_seen()[k].pass, passes[k]);
        EXPECT_EQ(mapped_pages_seen()[k].size, file_size);
    }
    const std::uint64_t a_bytes = 8 * (std::uint64_t(written.A.rows()) + 1 + 2 * std::uint64_t(written.A.nonZeros()));
    EXPECT_GE(mapped_pages_seen()[2].rss_bytes, file_size - (std::uint64_t(1) << 20)) << "the checks read it all";
    EXPECT_LE(mapped_pages_seen()[3].rss_bytes, file_size - a_bytes + (std::uint64_t(1) << 20))
        << "A's arrays were given back (" << a_bytes << " of " << file_size << " bytes)";
    // The pages given back were read again where needed: the QP is the one written, to the bit.
    ASSERT_EQ(read.A.nonZeros(), written.A.nonZeros());
    EXPECT_EQ(std::vector<double>(read.A.valuePtr(), read.A.valuePtr() + read.A.nonZeros()),
              std::vector<double>(written.A.valuePtr(), written.A.valuePtr() + written.A.nonZeros()));
    EXPECT_EQ(std::vector<int>(read.A.innerIndexPtr(), read.A.innerIndexPtr() + read.A.nonZeros()),
              std::vector<int>(written.A.innerIndexPtr(), written.A.innerIndexPtr() + written.A.nonZeros()));
    EXPECT_EQ(read.b, written.b);
    EXPECT_EQ(read.x0, written.x0);
    EXPECT_EQ(read.J.nonZeros(), written.J.nonZeros());

    // Nothing of the file stays mapped once the reader returns.
    std::ifstream maps("/proc/self/maps");
    std::string line;
    int mappings = 0;
    while (std::getline(maps, line)) mappings += line.find(path) != std::string::npos;
    EXPECT_EQ(mappings, 0);
    std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace cb
