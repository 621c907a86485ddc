#include "sim/collision/bvh.hpp"

#include <algorithm>
#include <limits>
#include <numeric>

namespace cb::sim {

void Bvh::build(const std::vector<Box3>& boxes)
{
    m_boxes = boxes;
    m_nodes.clear();
    m_order.resize(boxes.size());
    std::iota(m_order.begin(), m_order.end(), 0);
    if (boxes.empty()) return;
    std::vector<Eigen::Vector3d> centroids(boxes.size());
    for (size_t i = 0; i < boxes.size(); ++i) centroids[i] = boxes[i].center();
    m_nodes.reserve(2 * boxes.size() / 2 + 2);
    build_node(0, static_cast<int>(boxes.size()), centroids, 0);
}

int Bvh::build_node(int first, int count, std::vector<Eigen::Vector3d>& centroids, int depth)
{
    const int index = static_cast<int>(m_nodes.size());
    m_nodes.emplace_back();
    Box3 box, cbox;
    for (int k = 0; k < count; ++k) {
        const int prim = m_order[static_cast<size_t>(first) + static_cast<size_t>(k)];
        box.extend(m_boxes[static_cast<size_t>(prim)]);
        cbox.extend(centroids[static_cast<size_t>(prim)]);
    }
    m_nodes[static_cast<size_t>(index)].box = box;
    // Depth cap keeps the traversal stack (128) safe even for degenerate inputs.
    if (count <= 4 || depth > 60) {
        m_nodes[static_cast<size_t>(index)].first = first;
        m_nodes[static_cast<size_t>(index)].count = count;
        return index;
    }
    int axis = 0;
    (cbox.max() - cbox.min()).maxCoeff(&axis);
    const int mid = first + count / 2;
    std::nth_element(m_order.begin() + first, m_order.begin() + mid, m_order.begin() + first + count,
                     [&](int a, int b) {
                         return centroids[static_cast<size_t>(a)][axis] < centroids[static_cast<size_t>(b)][axis];
                     });
    const int left = build_node(first, mid - first, centroids, depth + 1);
    const int right = build_node(mid, first + count - mid, centroids, depth + 1);
    m_nodes[static_cast<size_t>(index)].left = left;
    m_nodes[static_cast<size_t>(index)].right = right;
    return index;
}

int Bvh::nearest(const Eigen::Vector3d& p, const std::function<double(int)>& distance2, double* best_d2) const
{
    double best = std::numeric_limits<double>::infinity();
    int best_prim = -1;
    if (!m_nodes.empty()) {
        // Best-first by box distance; a small explicit stack ordered nearest child last.
        std::vector<std::pair<double, int>> stack;
        stack.reserve(128);
        stack.emplace_back(m_nodes[0].box.squaredExteriorDistance(p), 0);
        while (!stack.empty()) {
            const auto [d, ni] = stack.back();
            stack.pop_back();
            if (d >= best) continue;
            const Node& node = m_nodes[static_cast<size_t>(ni)];
            if (node.count > 0) {
                for (int k = 0; k < node.count; ++k) {
                    const int prim = m_order[static_cast<size_t>(node.first) + static_cast<size_t>(k)];
                    if (m_boxes[static_cast<size_t>(prim)].squaredExteriorDistance(p) >= best) continue;
                    const double dd = distance2(prim);
                    if (dd < best) {
                        best = dd;
                        best_prim = prim;
                    }
                }
            } else {
                const double dl = m_nodes[static_cast<size_t>(node.left)].box.squaredExteriorDistance(p);
                const double dr = m_nodes[static_cast<size_t>(node.right)].box.squaredExteriorDistance(p);
                if (dl < dr) {
                    stack.emplace_back(dr, node.right);
                    stack.emplace_back(dl, node.left);
                } else {
                    stack.emplace_back(dl, node.left);
                    stack.emplace_back(dr, node.right);
                }
            }
        }
    }
    if (best_d2) *best_d2 = best;
    return best_prim;
}

}  // namespace cb::sim
