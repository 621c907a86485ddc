// libFuzzer entry point for the FCLIB reader (problems/fclib_io.cpp, issues 27 and 41). Each input
// picks one of three small valid problems (a global one with M in CSR and H in CSC, a start point
// and a solution; a global one as Siconos writes it, with triplets in CSparse's convention and M
// as its upper triangle; a local one) and a list of edits to it; the driver writes the edited file
// with plain HDF5 calls and gives it to read_fclib (friction dropped and asymmetry averaged or
// not, by the input's length), which must return a whole QP or throw cb::InputError. A crash, a sanitizer
// report, a hang, an exit() or any other exception is a finding. The HDF5 files are always
// well-formed HDF5 (libhdf5 and libfclib are not instrumented, and fuzzing HDF5's own format is
// not the point): what varies is every dataset of the FCLIB layout, its presence, type, rank,
// length, declared sizes and values. Empty input = the valid problem.
// Build: cmake -DCB_FUZZ=ON with CXX=clang++ (target fuzz_fclib), or see tests/fuzz/README.md.
#include "problems/fclib_io.hpp"
#include "tests/problems/hdf5_edit.hpp"

#include <fuzzer/FuzzedDataProvider.h>

#include <climits>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <unistd.h>
#include <vector>

namespace {

/// Every dataset of the layout the reader looks at, and the groups whose removal matters.
const char* const FIELDS[] = {"/fclib_global/spacedim",
                              "/fclib_global/M/nzmax",
                              "/fclib_global/M/m",
                              "/fclib_global/M/n",
                              "/fclib_global/M/nz",
                              "/fclib_global/M/p",
                              "/fclib_global/M/i",
                              "/fclib_global/M/x",
                              "/fclib_global/H/nzmax",
                              "/fclib_global/H/m",
                              "/fclib_global/H/n",
                              "/fclib_global/H/nz",
                              "/fclib_global/H/p",
                              "/fclib_global/H/i",
                              "/fclib_global/H/x",
                              "/fclib_global/G/n",
                              "/fclib_global/vectors/f",
                              "/fclib_global/vectors/w",
                              "/fclib_global/vectors/mu",
                              "/fclib_global/info/description",
                              "/fclib_global/info/title",
                              "/fclib_local/spacedim",
                              "/fclib_local/W/nzmax",
                              "/fclib_local/W/m",
                              "/fclib_local/W/n",
                              "/fclib_local/W/nz",
                              "/fclib_local/W/p",
                              "/fclib_local/W/i",
                              "/fclib_local/W/x",
                              "/fclib_local/V/n",
                              "/fclib_local/vectors/q",
                              "/fclib_local/vectors/mu",
                              "/solution/u",
                              "/guesses/1/r",
                              "/fclib_local",
                              "/guesses/number_of_guesses",
                              "/guesses/1/v",
                              "/solution/v",
                              "/solution/r",
                              "/fclib_global/M",
                              "/fclib_global/H",
                              "/fclib_global/vectors",
                              "/guesses",
                              "/solution",
                              "/fclib_global"};

long long fuzzed_integer(FuzzedDataProvider& in)
{
    static const long long SPECIAL[] = {
        0, 1, -1, -2, -3, 2, 3, 6, INT_MAX, INT_MIN, 2147483646, 2147483648LL, -2147483649LL, LLONG_MAX, LLONG_MIN};
    if (in.ConsumeBool()) return SPECIAL[in.ConsumeIntegralInRange<size_t>(0, std::size(SPECIAL) - 1)];
    return in.ConsumeIntegralInRange<long long>(-4, 12);
}

double fuzzed_real(FuzzedDataProvider& in)
{
    static const double SPECIAL[] = {
        0.0,      -0.0,      1.0,   -1.0,   2.0,   0.5, std::numeric_limits<double>::quiet_NaN(),
        INFINITY, -INFINITY, 1e308, 5e-324, 1e-300};
    if (in.ConsumeBool()) return SPECIAL[in.ConsumeIntegralInRange<size_t>(0, std::size(SPECIAL) - 1)];
    return in.ConsumeFloatingPoint<double>();
}

/// The valid problem: A = 2 I (3 x 3, CSR), J = [e1'; e2'] (H 3 x 6 in CSC), b = 1, c = (0, 1).
void write_valid(cb::test::Hdf5Edit& f)
{
    f.put_ints("/fclib_global/spacedim", {3}, {1});
    f.put_ints("/fclib_global/M/nzmax", {3}, {1});
    f.put_ints("/fclib_global/M/m", {3}, {1});
    f.put_ints("/fclib_global/M/n", {3}, {1});
    f.put_ints("/fclib_global/M/nz", {-2}, {1});
    f.put_ints("/fclib_global/M/p", {0, 1, 2, 3});
    f.put_ints("/fclib_global/M/i", {0, 1, 2});
    f.put_reals("/fclib_global/M/x", {2.0, 2.0, 2.0});
    f.put_ints("/fclib_global/H/nzmax", {2}, {1});
    f.put_ints("/fclib_global/H/m", {3}, {1});
    f.put_ints("/fclib_global/H/n", {6}, {1});
    f.put_ints("/fclib_global/H/nz", {-1}, {1});
    f.put_ints("/fclib_global/H/p", {0, 1, 1, 1, 2, 2, 2});
    f.put_ints("/fclib_global/H/i", {0, 1});
    f.put_reals("/fclib_global/H/x", {1.0, 1.0});
    f.put_reals("/fclib_global/vectors/f", {1.0, 1.0, 1.0});
    f.put_reals("/fclib_global/vectors/w", {0.0, 0.0, 0.0, -1.0, 0.0, 0.0});
    f.put_reals("/fclib_global/vectors/mu", {0.0, 0.0});
    f.put_text("/fclib_global/info/description", "{\"family\": \"fuzz\"}");
    f.put_ints("/guesses/number_of_guesses", {1}, {1});
    f.put_reals("/guesses/1/v", {0.0, 0.0, 0.0});
    f.put_reals("/solution/v", {0.5, 1.0, 0.5});
    f.put_reals("/solution/r", {0.0, 0.0, 0.0, 1.0, 0.0, 0.0});
}

/// The valid problem as Siconos and LMGC90 write it: the same QP with M (A = 2 I plus 0.5 at (0, 1))
/// as its upper triangle in triplets (p = columns, i = rows, x with nzmax values), H in triplets.
void write_valid_triplets(cb::test::Hdf5Edit& f)
{
    f.put_ints("/fclib_global/spacedim", {3}, {1});
    f.put_ints("/fclib_global/M/nzmax", {5}, {1});
    f.put_ints("/fclib_global/M/m", {3}, {1});
    f.put_ints("/fclib_global/M/n", {3}, {1});
    f.put_ints("/fclib_global/M/nz", {4}, {1});
    f.put_ints("/fclib_global/M/p", {0, 1, 1, 2});
    f.put_ints("/fclib_global/M/i", {0, 0, 1, 2});
    f.put_reals("/fclib_global/M/x", {2.0, 0.5, 2.0, 2.0, 7.0});
    f.put_ints("/fclib_global/H/nzmax", {2}, {1});
    f.put_ints("/fclib_global/H/m", {3}, {1});
    f.put_ints("/fclib_global/H/n", {6}, {1});
    f.put_ints("/fclib_global/H/nz", {2}, {1});
    f.put_ints("/fclib_global/H/p", {0, 3});
    f.put_ints("/fclib_global/H/i", {0, 1});
    f.put_reals("/fclib_global/H/x", {1.0, 1.0});
    f.put_reals("/fclib_global/vectors/f", {1.0, 1.0, 1.0});
    f.put_reals("/fclib_global/vectors/w", {0.0, 0.0, 0.0, -1.0, 0.0, 0.0});
    f.put_reals("/fclib_global/vectors/mu", {0.3, 0.0});
    f.put_text("/fclib_global/info/title", "LMGC dump");
}

/// A local problem of 2 contacts: W (6 x 6, CSR) with W_NN = [2 -1; -1 3], a solution and a guess.
void write_valid_local(cb::test::Hdf5Edit& f)
{
    f.put_ints("/fclib_local/spacedim", {3}, {1});
    f.put_ints("/fclib_local/W/nzmax", {8}, {1});
    f.put_ints("/fclib_local/W/m", {6}, {1});
    f.put_ints("/fclib_local/W/n", {6}, {1});
    f.put_ints("/fclib_local/W/nz", {-2}, {1});
    f.put_ints("/fclib_local/W/p", {0, 2, 3, 4, 6, 7, 8});
    f.put_ints("/fclib_local/W/i", {0, 3, 1, 2, 0, 3, 4, 5});
    f.put_reals("/fclib_local/W/x", {2.0, -1.0, 1.0, 1.0, -1.0, 3.0, 1.0, 1.0});
    f.put_reals("/fclib_local/vectors/q", {-1.0, 0.3, 0.4, 2.0, 0.0, 0.0});
    f.put_reals("/fclib_local/vectors/mu", {0.0, 0.0});
    f.put_reals("/solution/r", {0.5, 0.0, 0.0, 0.0, 0.0, 0.0});
    f.put_reals("/solution/u", {0.0, 0.0, 0.0, 1.5, 0.0, 0.0});
    f.put_ints("/guesses/number_of_guesses", {1}, {1});
    f.put_reals("/guesses/1/r", {0.1, 0.0, 0.0, 0.2, 0.0, 0.0});
}

void apply_edit(cb::test::Hdf5Edit& f, FuzzedDataProvider& in)
{
    const std::string field = FIELDS[in.ConsumeIntegralInRange<size_t>(0, std::size(FIELDS) - 1)];
    const size_t length = in.ConsumeIntegralInRange<size_t>(0, 24);
    switch (in.ConsumeIntegralInRange<int>(0, 6)) {
    case 0:
        f.remove(field);
        break;
    case 1: {
        std::vector<long long> v(length);
        for (auto& x : v) x = fuzzed_integer(in);
        f.put_ints(field, v, {hsize_t(length)});
        break;
    }
    case 2: {
        std::vector<double> v(length);
        for (auto& x : v) x = fuzzed_real(in);
        f.put_reals(field, v, {hsize_t(length)});
        break;
    }
    case 3:
        f.put_ints(field, {fuzzed_integer(in)});  // a scalar dataspace
        break;
    case 4:
        f.put_unwritten(field, in.ConsumeBool() ? hsize_t(length) : in.ConsumeIntegral<std::uint32_t>());
        break;
    case 5: {
        std::vector<long long> v(2 * length);
        for (auto& x : v) x = fuzzed_integer(in);
        f.put_ints(field, v, {hsize_t(length), 2});
        break;
    }
    default:
        f.put_text(field, in.ConsumeRandomLengthString(64));
        break;
    }
}

}  // namespace

// NOLINTNEXTLINE(readability-identifier-naming): libFuzzer's fixed entry point
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    // One scratch file per process, removed when libFuzzer exits.
    static const struct Scratch {
        std::string path = "/dev/shm/cb_fuzz_fclib_" + std::to_string(::getpid()) + ".hdf5";
        ~Scratch() { ::unlink(path.c_str()); }
    } scratch;
    const std::string& path = scratch.path;
    FuzzedDataProvider in(data, size);
    {
        cb::test::Hdf5Edit file(path, true);
        switch (size == 0 ? 0 : in.ConsumeIntegralInRange<int>(0, 2)) {
        case 0:
            write_valid(file);
            break;
        case 1:
            write_valid_triplets(file);
            break;
        default:
            write_valid_local(file);
            break;
        }
        for (int edits = 0; edits < 12 && in.remaining_bytes() > 0; ++edits) {
            try {
                apply_edit(file, in);
            } catch (const std::runtime_error&) {
                // HDF5 refused the edit (a dataset where a group is needed): the file stays as it was
            }
        }
    }
    try {
        cb::SnapshotExtras extras;
        cb::FclibReadOptions options;
        options.drop_friction = size % 2 == 1;
        options.symmetrise = size % 3 == 0;
        const cb::Qp qp = cb::read_fclib(path, &extras, options);
        // A returned problem must be whole: the dimensions agree.
        if (qp.b.size() != qp.n() || qp.x0.size() != qp.n() || qp.J.cols() != qp.n() || qp.c.size() != qp.m() ||
            qp.A.cols() != qp.n() || (extras.x_ref.size() != 0 && extras.x_ref.size() != qp.n()) ||
            (extras.lambda_ref.size() != 0 && extras.lambda_ref.size() != qp.m()))
            __builtin_trap();
    } catch (const cb::InputError&) {
        // the expected rejection of a bad file
    }
    return 0;
}
