#include "sim/render.hpp"

#include "problems/io_util.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <zlib.h>

namespace cb::sim {

namespace {
void put_u32(std::vector<std::uint8_t>& out, std::uint32_t v)
{
    for (int s = 24; s >= 0; s -= 8) out.push_back(static_cast<std::uint8_t>(v >> s));
}
void chunk(std::vector<std::uint8_t>& out, const char* type, const std::vector<std::uint8_t>& data)
{
    put_u32(out, static_cast<std::uint32_t>(data.size()));
    const size_t start = out.size();
    out.insert(out.end(), type, type + 4);
    out.insert(out.end(), data.begin(), data.end());
    // The CRC covers the type and the data, not the length.
    const uLong crc = crc32(0L, out.data() + start, static_cast<uInt>(out.size() - start));
    put_u32(out, static_cast<std::uint32_t>(crc));
}
}  // namespace

void write_png(const std::string& path, const Image& image)
{
    std::vector<std::uint8_t> raw;
    raw.reserve(static_cast<size_t>(image.height) * (1 + 3 * static_cast<size_t>(image.width)));
    for (int y = 0; y < image.height; ++y) {
        raw.push_back(0);  // filter type 0 (none) for every scanline
        const auto* row = image.rgb.data() + static_cast<size_t>(y) * image.width * 3;
        raw.insert(raw.end(), row, row + static_cast<size_t>(image.width) * 3);
    }
    uLongf zsize = compressBound(static_cast<uLong>(raw.size()));
    std::vector<std::uint8_t> z(zsize);
    if (compress2(z.data(), &zsize, raw.data(), static_cast<uLong>(raw.size()), 6) != Z_OK)
        throw_input_error(path, "", "zlib compression failed");
    z.resize(zsize);
    std::vector<std::uint8_t> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    std::vector<std::uint8_t> ihdr;
    put_u32(ihdr, static_cast<std::uint32_t>(image.width));
    put_u32(ihdr, static_cast<std::uint32_t>(image.height));
    ihdr.insert(ihdr.end(), {8, 2, 0, 0, 0});  // 8 bit, RGB, deflate, filter 0, no interlace
    chunk(png, "IHDR", ihdr);
    chunk(png, "IDAT", z);
    chunk(png, "IEND", {});
    AtomicFile out(path);  // every write checked, no partial picture left behind
    out.write(png.data(), png.size());
    out.commit();
}

View make_view(const Vec3& view_deg, const Vec3& lo, const Vec3& hi)
{
    View v;
    // Yaw about the world's y axis first, then pitch about the camera's x axis, then roll.
    const Vec3 r = view_deg * (M_PI / 180.0);
    v.rotation = (Eigen::AngleAxisd(r.z(), Vec3::UnitZ()) * Eigen::AngleAxisd(r.x(), Vec3::UnitX()) *
                  Eigen::AngleAxisd(r.y(), Vec3::UnitY()))
                     .toRotationMatrix();
    // Frame the 8 corners of the box in camera coordinates.
    Vec3 clo = Vec3::Constant(1e300), chi = Vec3::Constant(-1e300);
    for (int k = 0; k < 8; ++k) {
        const Vec3 p((k & 1) ? hi.x() : lo.x(), (k & 2) ? hi.y() : lo.y(), (k & 4) ? hi.z() : lo.z());
        const Vec3 q = v.rotation * p;
        clo = clo.cwiseMin(q);
        chi = chi.cwiseMax(q);
    }
    v.center = 0.5 * (clo + chi);
    v.half_extent = 0.55 * std::max({chi.x() - clo.x(), chi.y() - clo.y(), 1e-9});
    return v;
}

void render_tile(Image& image, int x0, int size, const View& view, const std::vector<ColoredSurface>& surfaces)
{
    std::vector<double> zbuf(static_cast<size_t>(size) * size, -std::numeric_limits<double>::infinity());
    const Vec3 light = Vec3(0.3, 0.5, 1.0).normalized();
    const double px = 0.5 * size / view.half_extent;
    for (const auto& s : surfaces) {
        const SurfaceMesh& m = *s.mesh;
        std::vector<Vec3> q(static_cast<size_t>(m.positions.rows()));
        for (Eigen::Index i = 0; i < m.positions.rows(); ++i) {
            const Vec3 c = view.rotation * Vec3(m.positions.row(i).transpose()) - view.center;
            q[static_cast<size_t>(i)] = Vec3(0.5 * size + c.x() * px, 0.5 * size - c.y() * px, c.z());
        }
        for (Eigen::Index f = 0; f < m.faces.rows(); ++f) {
            const Vec3& a = q[static_cast<size_t>(m.faces(f, 0))];
            const Vec3& b = q[static_cast<size_t>(m.faces(f, 1))];
            const Vec3& c = q[static_cast<size_t>(m.faces(f, 2))];
            const Vec3 wa = view.rotation * Vec3(m.positions.row(m.faces(f, 0)).transpose());
            const Vec3 wb = view.rotation * Vec3(m.positions.row(m.faces(f, 1)).transpose());
            const Vec3 wc = view.rotation * Vec3(m.positions.row(m.faces(f, 2)).transpose());
            Vec3 n = (wb - wa).cross(wc - wa);
            if (n.norm() == 0) continue;
            n.normalize();
            const double shade = 0.3 + 0.7 * std::abs(n.dot(light));  // two-sided
            const double area = (b.x() - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (b.y() - a.y());
            if (area == 0) continue;
            const int xmin = std::max(0, static_cast<int>(std::floor(std::min({a.x(), b.x(), c.x()}))));
            const int xmax = std::min(size - 1, static_cast<int>(std::ceil(std::max({a.x(), b.x(), c.x()}))));
            const int ymin = std::max(0, static_cast<int>(std::floor(std::min({a.y(), b.y(), c.y()}))));
            const int ymax = std::min(size - 1, static_cast<int>(std::ceil(std::max({a.y(), b.y(), c.y()}))));
            for (int y = ymin; y <= ymax; ++y)
                for (int x = xmin; x <= xmax; ++x) {
                    const double sx = x + 0.5, sy = y + 0.5;
                    const double w0 = ((b.x() - sx) * (c.y() - sy) - (c.x() - sx) * (b.y() - sy)) / area;
                    const double w1 = ((c.x() - sx) * (a.y() - sy) - (a.x() - sx) * (c.y() - sy)) / area;
                    const double w2 = 1.0 - w0 - w1;
                    if (w0 < 0 || w1 < 0 || w2 < 0) continue;
                    const double z = w0 * a.z() + w1 * b.z() + w2 * c.z();
                    double& zb = zbuf[static_cast<size_t>(y) * size + x];
                    if (z <= zb) continue;
                    zb = z;
                    std::uint8_t* p = image.rgb.data() + (static_cast<size_t>(y) * image.width + x0 + x) * 3;
                    for (int k = 0; k < 3; ++k)
                        p[k] = static_cast<std::uint8_t>(
                            std::clamp(255.0 * shade * s.color[static_cast<size_t>(k)], 0.0, 255.0));
                }
        }
    }
}

}  // namespace cb::sim
