#pragma once
/// A bounding-volume hierarchy of axis-aligned boxes (binary, median split on the longest
/// axis of the centroids, leaves of <= 4 primitives). Used for candidate search in collision
/// detection; tests/sim/test_bvh.cpp checks it against brute force.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <functional>
#include <vector>

namespace cb::sim {

using Box3 = Eigen::AlignedBox3d;

class Bvh {
public:
    Bvh() = default;
    explicit Bvh(const std::vector<Box3>& boxes) { build(boxes); }
    void build(const std::vector<Box3>& boxes);
    bool empty() const { return m_nodes.empty(); }
    const Box3& bounds() const { return m_nodes.front().box; }

    /// Calls visit(primitive) for every primitive whose box contains p.
    template <class Visit> void query_point(const Eigen::Vector3d& p, Visit&& visit) const
    {
        if (m_nodes.empty()) return;
        int stack[128];
        int top = 0;
        stack[top++] = 0;
        while (top > 0) {
            const Node& node = m_nodes[static_cast<size_t>(stack[--top])];
            if (!node.box.contains(p)) continue;
            if (node.count > 0) {
                for (int k = 0; k < node.count; ++k) {
                    const int prim = m_order[static_cast<size_t>(node.first) + static_cast<size_t>(k)];
                    if (m_boxes[static_cast<size_t>(prim)].contains(p)) visit(prim);
                }
            } else {
                stack[top++] = node.left;
                stack[top++] = node.right;
            }
        }
    }

    /// Calls visit(primitive) for every primitive whose box intersects `box`.
    template <class Visit> void query_box(const Box3& box, Visit&& visit) const
    {
        if (m_nodes.empty()) return;
        int stack[128];
        int top = 0;
        stack[top++] = 0;
        while (top > 0) {
            const Node& node = m_nodes[static_cast<size_t>(stack[--top])];
            if (!node.box.intersects(box)) continue;
            if (node.count > 0) {
                for (int k = 0; k < node.count; ++k) {
                    const int prim = m_order[static_cast<size_t>(node.first) + static_cast<size_t>(k)];
                    if (m_boxes[static_cast<size_t>(prim)].intersects(box)) visit(prim);
                }
            } else {
                stack[top++] = node.left;
                stack[top++] = node.right;
            }
        }
    }

    /// Nearest primitive to p under `distance2(primitive)` (squared distance, bounded below by
    /// the squared distance from p to the primitive's box). Returns -1 when empty.
    int nearest(const Eigen::Vector3d& p, const std::function<double(int)>& distance2, double* best_d2 = nullptr) const;

private:
    struct Node {
        Box3 box;
        int left = -1, right = -1;  ///< children (internal nodes)
        int first = 0, count = 0;   ///< range in m_order (leaves: count > 0)
    };
    int build_node(int first, int count, std::vector<Eigen::Vector3d>& centroids, int depth);
    std::vector<Node> m_nodes;
    std::vector<int> m_order;
    std::vector<Box3> m_boxes;
};

}  // namespace cb::sim
