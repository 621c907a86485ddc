// problems/io_util: special files refused without blocking, the JSON depth scan (brackets in
// strings do not count), and atomic writes that fail cleanly past a file-size limit.
#include "problems/io_util.hpp"
#include "solvers/core/types.hpp"

#include <gtest/gtest.h>

#include <csignal>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/wait.h>
#include <unistd.h>

namespace cb {
namespace {

namespace fs = std::filesystem;

fs::path scratch()
{
    static const fs::path dir = [] {
        fs::path d = fs::temp_directory_path() / ("cb_test_io_" + std::to_string(::getpid()));
        fs::remove_all(d);
        fs::create_directories(d);
        return d;
    }();
    return dir;
}

template <typename F> std::string io_error_of(F&& f)
{
    try {
        f();
    } catch (const InputError& e) {
        return e.what();
    }
    return "(no error)";
}

TEST(IoUtil, SpecialFilesAreRefusedWithoutBlocking)
{
    const fs::path fifo = scratch() / "fifo";
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
    EXPECT_EQ(io_error_of([&] { read_regular_file(fifo.string()); }), fifo.string() + ": not a regular file (a FIFO)");
    EXPECT_EQ(io_error_of([&] { read_json_checked(scratch().string()); }),
              scratch().string() + ": not a regular file (a folder)");
    EXPECT_EQ(io_error_of([&] { require_regular_file("/dev/null"); }), "/dev/null: not a regular file (a device)");
    EXPECT_EQ(io_error_of([&] { read_regular_file((scratch() / "missing").string()); }),
              (scratch() / "missing").string() + ": cannot open: No such file or directory");
}

TEST(IoUtil, JsonDepthCountsBracketsOutsideStringsOnly)
{
    // 64 levels pass, 65 do not; brackets inside strings (escaped quotes too) are text.
    const std::string ok = std::string(64, '[') + std::string(64, ']');
    EXPECT_NO_THROW(parse_json_text(ok, "ok.json"));
    const std::string deep = std::string(65, '[') + std::string(65, ']');
    EXPECT_EQ(io_error_of([&] { parse_json_text(deep, "deep.json"); }),
              "deep.json: JSON nested deeper than 64 levels (at byte 64)");
    const std::string text = R"({"a": "[[[[\"{{{{", "b": [1, {"c": "]]]]"}]})";
    const nlohmann::json j = parse_json_text(std::string(60, '[') + text + std::string(60, ']'), "s.json");
    EXPECT_EQ(j[0][0][0][0].size(), 1u);
    EXPECT_EQ(io_error_of([&] { parse_json_text("{\"a\": }", "bad.json"); }).rfind("bad.json: not valid JSON: ", 0),
              0u);
    const std::string three = "[[[";
    EXPECT_EQ(io_error_of([&] { check_json_depth(three.data(), three.data() + three.size(), "h", "header", 2); }),
              "h: header: JSON nested deeper than 2 levels (at byte 2)");
}

TEST(IoUtil, AtomicWritePastAFileSizeLimitLeavesNothing)
{
    const fs::path target = scratch() / "out.bin";
    write_file_atomic(target.string(), "old content\n");
    // In a child: RLIMIT_FSIZE of 4 kB, SIGXFSZ ignored (as contactbench's main() does).
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
        std::signal(SIGXFSZ, SIG_IGN);
        const rlimit limit{4096, 4096};
        ::setrlimit(RLIMIT_FSIZE, &limit);
        const std::string message = io_error_of([&] { write_file_atomic(target.string(), std::string(100000, 'x')); });
        ::_exit(message == target.string() + ": write failed: File too large (nothing written)" ? 0 : 1);
    }
    int status = 0;
    ASSERT_EQ(::waitpid(child, &status, 0), child);
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 0) << "the child saw another message";
    std::ifstream in(target);
    EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), "old content\n");  // the old file is whole
    size_t leftovers = 0;
    for (const auto& e : fs::directory_iterator(scratch()))
        if (e.path().filename().string().find(".tmp.") != std::string::npos) ++leftovers;
    EXPECT_EQ(leftovers, 0u);
}

// Issue 27: the temporary name is predictable; an entry planted there is removed, never followed.
TEST(IoUtil, AtomicWriteNeverFollowsAPlantedTemporary)
{
    const fs::path victim = scratch() / "victim.txt", target = scratch() / "planted.txt";
    std::ofstream(victim) << "precious\n";
    fs::create_symlink(victim, scratch() / ("planted.txt.tmp." + std::to_string(::getpid())));
    write_file_atomic(target.string(), "new\n");
    std::ifstream in(victim), out(target);
    EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), "precious\n");
    EXPECT_EQ(std::string(std::istreambuf_iterator<char>(out), {}), "new\n");
    EXPECT_FALSE(fs::is_symlink(target));
}

TEST(IoUtil, SpecialTargetsAreWrittenThroughOrRefusedNeverReplaced)
{
    const fs::path fifo = scratch() / "out.fifo";
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
    EXPECT_EQ(io_error_of([&] { write_file_atomic(fifo.string(), "x"); }),
              fifo.string() + ": is a FIFO with no reader: nothing written");
    EXPECT_EQ(io_error_of([&] { AtomicFile f(fifo.string(), SpecialTarget::REFUSE); }),
              fifo.string() + ": is a FIFO: not replaced (this output needs a regular file)");
    EXPECT_EQ(io_error_of([&] { write_file_atomic(scratch().string(), "x"); }),
              scratch().string() + ": is a folder: not replaced (name a file)");
    EXPECT_EQ(io_error_of([&] { write_file_atomic("", "x"); }),
              "(empty path): an output file name is required, got \"\"");
    // Twins of /dev/null and /dev/full made here (root only), never the machine's own: a
    // regression would replace them.
    const fs::path null_twin = scratch() / "null", full_twin = scratch() / "full";
    struct stat st {};
    if (::mknod(null_twin.c_str(), S_IFCHR | 0666, makedev(1, 3)) == 0 &&
        ::mknod(full_twin.c_str(), S_IFCHR | 0666, makedev(1, 7)) == 0) {
        EXPECT_EQ(io_error_of([&] { write_file_atomic(full_twin.string(), "x"); }),
                  full_twin.string() + ": write failed: No space left on device");
        write_file_atomic(null_twin.string(), "discarded");
        ASSERT_EQ(::lstat(null_twin.c_str(), &st), 0);
        EXPECT_TRUE(S_ISCHR(st.st_mode));
        ASSERT_EQ(::lstat(full_twin.c_str(), &st), 0);
        EXPECT_TRUE(S_ISCHR(st.st_mode));
    }
    ASSERT_EQ(::lstat(fifo.c_str(), &st), 0);
    EXPECT_TRUE(S_ISFIFO(st.st_mode));
}

// `--json /dev/stdout > f` as root replaced /dev/stdout (a link) by a regular file: nothing is
// created or renamed under /dev or /proc; a file behind /proc/self/fd/N is appended to.
TEST(IoUtil, DescriptorLinksAreWrittenThroughNeverReplaced)
{
    const fs::path behind = scratch() / "behind.txt";
    const int fd = ::open(behind.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ASSERT_GE(fd, 0);
    ASSERT_EQ(::write(fd, "summary\n", 8), 8);
    const std::string link = "/proc/self/fd/" + std::to_string(fd);
    write_file_atomic(link, "{\"json\": 1}\n");
    EXPECT_EQ(io_error_of([&] { AtomicFile f(link, SpecialTarget::REFUSE); }),
              link + ": is under /dev or /proc: this output needs a regular file of its own");
    EXPECT_EQ(io_error_of([&] { write_file_atomic("/proc/self/cb-no-such-file", "x"); }),
              "/proc/self/cb-no-such-file: is under /dev or /proc: only an existing device or stream is written there");
    ::close(fd);
    std::ifstream in(behind);
    EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), "summary\n{\"json\": 1}\n");
}

TEST(IoUtil, ReplaceDirLeavesNoOldFolder)
{
    const fs::path target = scratch() / "folder", staged = scratch() / "folder.tmp.1";
    fs::create_directories(target);
    std::ofstream(target / "a") << "old";
    fs::create_directories(staged);
    std::ofstream(staged / "a") << "new";
    replace_dir(staged.string(), target.string());
    std::ifstream in(target / "a");
    EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), "new");
    EXPECT_FALSE(fs::exists(staged));
    for (const auto& e : fs::directory_iterator(scratch()))
        EXPECT_EQ(e.path().filename().string().find("folder.old"), std::string::npos) << e.path();
}

class CleanUp : public ::testing::Environment {
public:
    void TearDown() override { fs::remove_all(scratch()); }
};
const auto* const CLEAN_UP = ::testing::AddGlobalTestEnvironment(new CleanUp);

}  // namespace
}  // namespace cb
