// One BLAS thread unless the user chose otherwise (blas_threads.hpp).
#include "harness/blas_threads.hpp"

#include <cstdlib>
#include <dlfcn.h>

namespace cb {

namespace {
// Looked up in the loaded libraries: libblas.so.3 may be OpenBLAS, BLIS or the reference BLAS.
template <class F> F openblas_function(const char* name)
{
    return reinterpret_cast<F>(::dlsym(RTLD_DEFAULT, name));  // NOLINT(cppcoreguidelines-pro-type-reinterpret-cast)
}
}  // namespace

void limit_blas_threads()
{
    if (std::getenv("OPENBLAS_NUM_THREADS") != nullptr) return;
    ::setenv("OPENBLAS_NUM_THREADS", "1", 0);  // for child processes
    // The library read the (unset) variable when it loaded, before main: set the count directly.
    if (auto set = openblas_function<void (*)(int)>("openblas_set_num_threads")) set(1);
}

int blas_threads()
{
    auto get = openblas_function<int (*)()>("openblas_get_num_threads");
    return get != nullptr ? get() : 0;
}

}  // namespace cb
