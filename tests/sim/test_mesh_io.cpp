// Mesh readers (every format, one tet or a cube each) and their error messages; the
// tetrahedraliser; the PNG writer.
#include "sim/mesh_io.hpp"
#include "sim/render.hpp"
#include "sim/tetrahedralize.hpp"
#include "tests/sim/input_error.hpp"

#include <gtest/gtest.h>
#include <cstdio>
#include <fstream>
#include <functional>
#include <unistd.h>
#include <zlib.h>

using namespace cb;
using namespace cb::sim;

namespace {
std::string tmp_path(const std::string& name)
{
    const char* dir = std::getenv("TMPDIR");
    return std::string(dir ? dir : "/tmp") + "/cb_test_mesh_io_" + std::to_string(::getpid()) + "_" + name;
}
std::string write(const std::string& name, const std::string& text)
{
    std::string p = tmp_path(name);
    std::ofstream(p) << text;
    return p;
}
void expect_unit_tet(const TetMesh& m)
{
    ASSERT_EQ(m.vertices(), 4);
    ASSERT_EQ(m.tet_count(), 1);
    EXPECT_NEAR(mesh_volume(m), 1.0 / 6.0, 1e-15);  // oriented positively whatever the file order
}
}  // namespace

TEST(MeshIo, ReadsEveryTetFormat)
{
    // The file lists the tet with negative orientation (0 2 1 3) so orientation is fixed on read.
    expect_unit_tet(
        read_abq(write("t.abq", "*HEADING\n*NODE\n1, 0,0,0\n2, 1,0,0\n3, 0,1,0\n4, 0,0,1\n"
                                "*ELEMENT, TYPE=C3D4, ELSET=E\n1, 1,3,2,4\n*ELSET, ELSET=EALL, GENERATE\n1,1,1\n")));
    write("t.node", "# nodes\n4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n");
    expect_unit_tet(read_tetgen(write("t.ele", "1 4 0\n0 0 2 1 3\n")));
    expect_unit_tet(read_gmsh(write(
        "t22.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n"
                   "$Elements\n2\n1 2 2 0 1 1 2 3\n2 4 2 0 1 1 3 2 4\n$EndElements\n")));
    expect_unit_tet(read_gmsh(
        write("t41.msh", "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Entities\n0 0 0 1\n1 0 0 0 1 1 1 0 0\n$EndEntities\n"
                         "$Nodes\n1 4 1 4\n3 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n$EndNodes\n"
                         "$Elements\n1 1 1 1\n3 1 4 1\n1 1 3 2 4\n$EndElements\n")));
    expect_unit_tet(read_medit(
        write("t.mesh", "MeshVersionFormatted 1\nDimension\n3\nVertices\n4\n0 0 0 0\n1 0 0 0\n0 1 0 0\n0 0 1 0\n"
                        "Triangles\n1\n1 2 3 0\nTetrahedra\n1\n1 3 2 4 0\nEnd\n")));
    expect_unit_tet(read_tet_mesh(tmp_path("t.abq")));
}

TEST(MeshIo, ReadsSurfaces)
{
    // COFF with colour columns, a quad fan-triangulated.
    const SurfaceMesh off =
        read_off(write("s.off", "COFF\n# comment\n4 2 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n1 1 0 0 0 255 255\n"
                                "0 1 0 9 9 9 255\n4 0 1 2 3\n3 0 2 1 10 20 30\n"));
    EXPECT_EQ(off.positions.rows(), 4);
    EXPECT_EQ(off.faces.rows(), 3);
    const SurfaceMesh obj =
        read_obj(write("s.obj", "mtllib x.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\nf -3 -1 -2\n"));
    EXPECT_EQ(obj.faces.rows(), 2);
    EXPECT_EQ(obj.faces(1, 1), 2);
}

TEST(MeshIo, ErrorsNameFileLineAndProblem)
{
    const std::string abq =
        write("bad.abq", "*NODE\n1, 0,0,0\n2, 1,0,0\n3, 0,1,0\n4, 0,0,1\n*ELEMENT, TYPE=C3D4\n1, 1,2,3\n");
    EXPECT_EQ(test::input_error_of([&] { read_abq(abq); }),
              abq + ": line 7: expected 5 integers 'id,n1,n2,n3,n4', got '1, 1,2,3'");
    const std::string abq2 = write("bad2.abq", "*NODE\n1, 0,0,zero\n");
    EXPECT_EQ(test::input_error_of([&] { read_abq(abq2); }), abq2 + ": line 2: expected a finite number, got 'zero'");
    const std::string abq3 =
        write("bad3.abq", "*NODE\n1, 0,0,0\n2, 1,0,0\n3, 0,1,0\n4, 0,0,1\n*ELEMENT, TYPE=C3D4\n1, 1,2,3,9\n");
    EXPECT_EQ(test::input_error_of([&] { read_abq(abq3); }), abq3 + ": line 7: tet refers to undefined vertex id 9");
    const std::string flat =
        write("flat.abq", "*NODE\n1, 0,0,0\n2, 1,0,0\n3, 0,1,0\n4, 1,1,0\n*ELEMENT, TYPE=C3D4\n1, 1,2,3,4\n");
    EXPECT_NE(test::input_error_of([&] { read_abq(flat); }).find(flat + ": tet 1: degenerate"), std::string::npos);
    const std::string off = write("bad.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n");
    EXPECT_EQ(test::input_error_of([&] { read_off(off); }), off + ": line 6: vertex index 7 out of range (3 vertices)");
    const std::string msh = write("bad.msh", "$MeshFormat\n2.2 1 8\n$EndMeshFormat\n");
    EXPECT_NE(test::input_error_of([&] { read_gmsh(msh); }).find(msh + ": line 2: only ASCII"), std::string::npos);
    EXPECT_NE(test::input_error_of([&] {
                  read_tet_mesh(tmp_path("missing.abq"));
              }).find("missing.abq: cannot open: No such file or directory"),
              std::string::npos);
    EXPECT_NE(test::input_error_of([&] { read_tet_mesh("x.vtk"); }).find("unknown tet mesh extension '.vtk'"),
              std::string::npos);
}

TEST(Tetrahedralize, OctahedronVolumeConvergesAndQualityIsReported)
{
    // Regular octahedron |x|+|y|+|z| <= 1, volume 4/3.
    SurfaceMesh s;
    s.positions.resize(6, 3);
    s.positions << 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1;
    s.faces.resize(8, 3);
    s.faces << 0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5;
    const InsideTest inside(s);
    EXPECT_TRUE(inside.inside(Vec3(0.1, 0.2, 0.3)));
    EXPECT_FALSE(inside.inside(Vec3(0.5, 0.4, 0.3)));
    double previous_error = 1e300;
    for (int res : {8, 16, 32}) {
        const TetMesh m = tetrahedralize(s, TetrahedralizeOptions{res}, "octahedron");
        const double err = std::abs(mesh_volume(m) - 4.0 / 3.0);
        EXPECT_LT(err, previous_error);
        previous_error = err;
        const MeshQuality q = mesh_quality(m);
        EXPECT_NEAR(q.min_dihedral_deg, 45.0, 1e-6);  // Kuhn tets of a cube grid
        EXPECT_GT(q.min_volume_ratio, 0.3);
    }
    EXPECT_LT(previous_error, 0.1);
}

TEST(Png, WritesAValidFile)
{
    Image img(3, 2, 0);
    img.rgb[0] = 255;
    const std::string p = tmp_path("x.png");
    write_png(p, img);
    std::ifstream in(p, std::ios::binary);
    std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    ASSERT_GT(bytes.size(), 40u);
    EXPECT_EQ(bytes[1], 'P');
    EXPECT_EQ(bytes[12], 'I');  // IHDR first
    // Width 3, height 2 (big-endian).
    EXPECT_EQ(bytes[19], 3);
    EXPECT_EQ(bytes[23], 2);
    // The IHDR CRC matches zlib's crc32 over type + data.
    const uLong crc = crc32(0L, bytes.data() + 12, 17);
    EXPECT_EQ(bytes[29], (crc >> 24) & 0xff);
    EXPECT_EQ(bytes[32], crc & 0xff);
}
