#pragma once
/// A small software rasteriser (orthographic, flat shading, z-buffer) and a PNG writer (zlib),
/// for the picture strips `contactbench simulate` writes.
#include "sim/tet_mesh.hpp"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace cb::sim {

struct Image {
    int width = 0, height = 0;
    std::vector<std::uint8_t> rgb;  ///< row-major, 3 bytes per pixel
    Image(int w, int h, std::uint8_t fill = 255) : width(w), height(h), rgb(static_cast<size_t>(w) * h * 3, fill) {}
};

/// Writes an 8-bit RGB PNG (filter 0, zlib-deflated IDAT). Throws InputError on IO failure.
void write_png(const std::string& path, const Image& image);

struct ColoredSurface {
    const SurfaceMesh* mesh;
    std::array<double, 3> color;  ///< 0..1
};

/// Orthographic view: world -> camera rotation R = Rz(z) Rx(x) Ry(y) from degrees (yaw y about
/// the world's up axis, then pitch x: positive looks down), framing the box [lo, hi].
struct View {
    Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
    Vec3 center = Vec3::Zero();
    double half_extent = 1.0;  ///< world units from the centre to the tile's edge
};
View make_view(const Vec3& view_deg, const Vec3& lo, const Vec3& hi);

/// Draws surfaces into the tile of `image` starting at column x0 (tile is size x size).
void render_tile(Image& image, int x0, int size, const View& view, const std::vector<ColoredSurface>& surfaces);

}  // namespace cb::sim
