#include "solvers/a_product.hpp"

#include <atomic>

namespace cb {

namespace {

std::atomic<long> g_a_products{0};

}  // namespace

// Out of line on purpose: one symbol that every counted product goes through.
void a_product(const SpMat& A, const Vec& x, Vec& y)
{
    y.noalias() = A * x;
    g_a_products.fetch_add(1, std::memory_order_relaxed);
}

Vec a_product(const SpMat& A, const Vec& x)
{
    Vec y;
    a_product(A, x, y);
    return y;
}

long a_product_count() { return g_a_products.load(std::memory_order_relaxed); }

}  // namespace cb
