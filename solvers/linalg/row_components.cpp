// Connected components of J's row graph (rows joined through shared vertices), by union-find.
#include "solvers/linalg/row_components.hpp"
#include "solvers/linalg/disjoint_sets.hpp"

#include <algorithm>
#include <numeric>

namespace cb {

int RowComponents::largest() const
{
    int best = 0;
    for (int k = 0; k < count(); ++k) best = std::max(best, size(k));
    return best;
}

int RowComponents::singletons() const
{
    int ones = 0;
    for (int k = 0; k < count(); ++k) ones += size(k) == 1;
    return ones;
}

RowComponents find_row_components(const SpMat& J)
{
    const int m = static_cast<int>(J.rows());
    DisjointSets sets(m);
    // The first row seen on each vertex; every later row on it joins that row's set.
    std::vector<int> owner(static_cast<size_t>(J.cols() / 3 + 1), -1);
    for (int i = 0; i < m; ++i)
        for (SpMat::InnerIterator it(J, i); it; ++it) {
            if (it.value() == 0.0) continue;
            int& o = owner[static_cast<size_t>(it.col() / 3)];
            if (o < 0)
                o = i;
            else
                sets.join(o, i);
        }
    RowComponents rc;
    int count = 0;
    rc.of_row = sets.labels(count);
    std::vector<int> sizes(static_cast<size_t>(count), 0);
    for (int c : rc.of_row) ++sizes[static_cast<size_t>(c)];
    rc.start.assign(sizes.size() + 1, 0);
    for (size_t k = 0; k < sizes.size(); ++k) rc.start[k + 1] = rc.start[k] + sizes[k];
    rc.rows.resize(static_cast<size_t>(m));
    std::vector<int> fill(rc.start.begin(), rc.start.end() - 1);
    for (int i = 0; i < m; ++i)
        rc.rows[static_cast<size_t>(fill[static_cast<size_t>(rc.of_row[static_cast<size_t>(i)])]++)] = i;
    return rc;
}

}  // namespace cb
