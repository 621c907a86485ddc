#pragma once
/// Union-find over 0..n-1 (path halving): the connected components of a graph given edge by edge,
/// numbered 0, 1, ... in the order of their smallest member (so independent of the union order).
/// Used for the bodies of A's vertex graph (solvers/measure/body_motion.*, solvers/mprgp/mprgp_deflation.*) and
/// the row graph's components (solvers/linalg/row_components.*).
#include <cstddef>
#include <numeric>
#include <vector>

namespace cb {

class DisjointSets {
public:
    explicit DisjointSets(int n) : m_parent(static_cast<size_t>(n)) { std::iota(m_parent.begin(), m_parent.end(), 0); }

    int find(int v)
    {
        while (m_parent[static_cast<size_t>(v)] != v) {
            m_parent[static_cast<size_t>(v)] = m_parent[static_cast<size_t>(m_parent[static_cast<size_t>(v)])];
            v = m_parent[static_cast<size_t>(v)];
        }
        return v;
    }
    /// The larger root hangs under the smaller, so a component's root is its smallest member and a
    /// graph met in index order (a mesh) keeps its trees shallow; labels() do not depend on it.
    void join(int a, int b)
    {
        a = find(a);
        b = find(b);
        if (a < b) m_parent[static_cast<size_t>(b)] = a;
        if (b < a) m_parent[static_cast<size_t>(a)] = b;
    }
    /// The component of every member, numbered by first appearance; `count` receives how many.
    std::vector<int> labels(int& count)
    {
        std::vector<int> id_of_root(m_parent.size(), -1), label(m_parent.size());
        count = 0;
        for (size_t v = 0; v < m_parent.size(); ++v) {
            int& id = id_of_root[static_cast<size_t>(find(static_cast<int>(v)))];
            if (id < 0) id = count++;
            label[v] = id;
        }
        return label;
    }

private:
    std::vector<int> m_parent;
};

}  // namespace cb
