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

double a_product_dots(const SpMat& A, const Vec& x, Vec& y, const Vec& w, double& xw)
{
    if (!A.isCompressed()) {  // the raw loop below reads a compressed row-major matrix
        a_product(A, x, y);
        xw = x.dot(w);
        return x.dot(y);
    }
    y.resize(A.rows());
    const int* __restrict outer = A.outerIndexPtr();
    const int* __restrict inner = A.innerIndexPtr();
    const double* __restrict val = A.valuePtr();
    const double* __restrict px = x.data();
    const double* __restrict pw = w.data();
    double* __restrict py = y.data();
    double xy = 0.0, dot_w = 0.0;
    for (Eigen::Index i = 0; i < A.rows(); ++i) {
        double s = 0.0;
        for (int k = outer[i]; k < outer[i + 1]; ++k) s += val[k] * px[inner[k]];
        py[i] = s;
        xy += px[i] * s;
        dot_w += px[i] * pw[i];
    }
    g_a_products.fetch_add(1, std::memory_order_relaxed);
    xw = dot_w;
    return xy;
}

Vec a_product(const SpMat& A, const Vec& x)
{
    Vec y;
    a_product(A, x, y);
    return y;
}

void a_product(const AOperator& A, const Vec& x, Vec& y) { a_product(A.csr(), x, y); }

double a_product_dots(const AOperator& A, const Vec& x, Vec& y, const Vec& w, double& xw)
{
    return a_product_dots(A.csr(), x, y, w, xw);
}

Vec a_product(const AOperator& A, const Vec& x) { return a_product(A.csr(), x); }

long a_product_count() { return g_a_products.load(std::memory_order_relaxed); }

}  // namespace cb
