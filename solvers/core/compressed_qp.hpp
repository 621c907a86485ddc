#pragma once
/// A QP view whose A and J are in Eigen's compressed storage. A matrix filled by insert() and not
/// yet makeCompressed() leaves room after each row, and kernels that walk a row as
/// outer[i]..outer[i + 1] would read that room. QPs read from files are always compressed (then
/// this holds no copy); a QP built in code may not be.
#include "solvers/core/qp.hpp"

namespace cb {

class CompressedQpView {
public:
    explicit CompressedQpView(const QpView& qp)
        : m_A_copy(compressed_copy(qp.A)),
          m_J_copy(compressed_copy(qp.J)), m_view{qp.A.isCompressed() ? qp.A : m_A_copy,
                                                  qp.b,
                                                  qp.J.isCompressed() ? qp.J : m_J_copy,
                                                  qp.c,
                                                  qp.x0,
                                                  qp.length,
                                                  qp.friction,
                                                  qp.a_symmetric}  // a compressed copy keeps A's values
    {
    }
    CompressedQpView(const CompressedQpView&) = delete;
    CompressedQpView& operator=(const CompressedQpView&) = delete;

    const QpView& view() const { return m_view; }

private:
    /// Empty when m is compressed already (the view then refers to the caller's matrix).
    static SpMat compressed_copy(const SpMat& m)
    {
        if (m.isCompressed()) return SpMat();
        SpMat copy = m;
        copy.makeCompressed();
        return copy;
    }

    SpMat m_A_copy;
    SpMat m_J_copy;
    QpView m_view;
};

}  // namespace cb
