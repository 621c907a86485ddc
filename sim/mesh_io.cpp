#include "sim/mesh_io.hpp"

#include "problems/io_util.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <unordered_map>

namespace cb::sim {
namespace {

std::string lower(std::string s)
{
    for (auto& ch : s) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    return s;
}

std::string extension(const std::string& path)
{
    const auto slash = path.find_last_of('/');
    const auto dot = path.find_last_of('.');
    if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
    return lower(path.substr(dot));
}

std::string trim(const std::string& s)
{
    size_t a = 0, b = s.size();
    while (a < b && std::isspace(static_cast<unsigned char>(s[a]))) ++a;
    while (b > a && std::isspace(static_cast<unsigned char>(s[b - 1]))) --b;
    return s.substr(a, b - a);
}

/// Line-by-line reader that knows where it is, for error messages.
class LineReader {
public:
    LineReader(const std::string& path, char comment)
        : m_path(path), m_comment(comment), m_in((require_regular_file(path), path))
    {
        if (!m_in) throw_input_error(path, "", "cannot open file");
    }
    /// Next non-empty line (comments stripped), split into tokens at whitespace and `separators`.
    bool next(std::vector<std::string>& tokens, const char* separators = "")
    {
        std::string line;
        while (std::getline(m_in, line)) {
            ++m_line;
            if (m_comment) {
                const auto c = line.find(m_comment);
                if (c != std::string::npos) line.erase(c);
            }
            m_text = trim(line);
            if (m_text.empty()) continue;
            tokens.clear();
            std::string cur;
            for (char ch : m_text) {
                if (std::isspace(static_cast<unsigned char>(ch)) || std::strchr(separators, ch)) {
                    if (!cur.empty()) tokens.push_back(cur);
                    cur.clear();
                } else
                    cur += ch;
            }
            if (!cur.empty()) tokens.push_back(cur);
            if (!tokens.empty()) return true;
        }
        m_text.clear();
        return false;
    }
    [[noreturn]] void fail(const std::string& what) const
    {
        throw_input_error(m_path, "line " + std::to_string(m_line), what);
    }
    [[noreturn]] void fail_eof(const std::string& what) const
    {
        throw_input_error(m_path, "line " + std::to_string(m_line), "unexpected end of file: " + what);
    }
    double real(const std::string& token) const
    {
        errno = 0;
        char* end = nullptr;
        const double v = std::strtod(token.c_str(), &end);
        if (end == token.c_str() || *end != '\0' || errno == ERANGE || !std::isfinite(v))
            fail("expected a finite number, got '" + token + "'");
        return v;
    }
    long integer(const std::string& token) const
    {
        errno = 0;
        char* end = nullptr;
        const long v = std::strtol(token.c_str(), &end, 10);
        if (end == token.c_str() || *end != '\0' || errno == ERANGE) fail("expected an integer, got '" + token + "'");
        return v;
    }
    const std::string& text() const { return m_text; }
    const std::string& path() const { return m_path; }
    long line() const { return m_line; }

private:
    std::string m_path;
    char m_comment;
    std::ifstream m_in;
    long m_line = 0;
    std::string m_text;
};

/// Collects nodes by file id and tets by file ids, then maps ids to 0-based rows.
struct IdMesh {
    std::vector<long> node_ids;
    std::vector<Vec3> nodes;
    std::vector<std::array<long, 4>> tets;
    std::vector<long> tet_lines;

    TetMesh finish(const std::string& path)
    {
        if (nodes.empty()) throw_input_error(path, "", "no vertices found");
        if (tets.empty()) throw_input_error(path, "", "no tetrahedra found");
        std::unordered_map<long, int> index;
        index.reserve(nodes.size() * 2);
        for (size_t i = 0; i < node_ids.size(); ++i)
            if (!index.emplace(node_ids[i], static_cast<int>(i)).second)
                throw_input_error(path, "", "vertex id " + std::to_string(node_ids[i]) + " defined twice");
        TetMesh mesh;
        mesh.positions.resize(static_cast<Eigen::Index>(nodes.size()), 3);
        for (size_t i = 0; i < nodes.size(); ++i)
            mesh.positions.row(static_cast<Eigen::Index>(i)) = nodes[i].transpose();
        mesh.tets.resize(static_cast<Eigen::Index>(tets.size()), 4);
        for (size_t t = 0; t < tets.size(); ++t)
            for (int k = 0; k < 4; ++k) {
                const auto it = index.find(tets[t][k]);
                if (it == index.end())
                    throw_input_error(path, "line " + std::to_string(tet_lines[t]),
                                      "tet refers to undefined vertex id " + std::to_string(tets[t][k]));
                mesh.tets(static_cast<Eigen::Index>(t), k) = it->second;
            }
        orient_tets(mesh, path);
        return mesh;
    }
};

}  // namespace

TetMesh read_abq(const std::string& path)
{
    LineReader in(path, 0);
    IdMesh m;
    enum { NONE, NODE, ELEMENT, OTHER } section = NONE;
    std::vector<std::string> tok;
    while (in.next(tok, ",")) {
        if (in.text().rfind("**", 0) == 0) continue;  // Abaqus comment
        if (in.text()[0] == '*') {
            const std::string key = lower(in.text());
            if (key.rfind("*node", 0) == 0 && key.rfind("*node output", 0) != 0)
                section = NODE;
            else if (key.rfind("*element", 0) == 0) {
                if (key.find("c3d4") == std::string::npos)
                    in.fail("only '*ELEMENT, TYPE=C3D4' (linear tets) is supported, got '" + in.text() + "'");
                section = ELEMENT;
            } else
                section = OTHER;
            continue;
        }
        if (section == NODE) {
            if (tok.size() < 4) in.fail("expected 'id,x,y,z', got '" + in.text() + "'");
            m.node_ids.push_back(in.integer(tok[0]));
            m.nodes.emplace_back(in.real(tok[1]), in.real(tok[2]), in.real(tok[3]));
        } else if (section == ELEMENT) {
            if (tok.size() != 5) in.fail("expected 5 integers 'id,n1,n2,n3,n4', got '" + in.text() + "'");
            m.tets.push_back({in.integer(tok[1]), in.integer(tok[2]), in.integer(tok[3]), in.integer(tok[4])});
            m.tet_lines.push_back(in.line());
        } else if (section == NONE)
            in.fail("expected a '*NODE' section first, got '" + in.text() + "'");
    }
    return m.finish(path);
}

TetMesh read_tetgen(const std::string& path)
{
    const std::string ext = extension(path);
    const std::string stem = path.substr(0, path.size() - ext.size());
    const std::string node_path = stem + ".node", ele_path = stem + ".ele";
    IdMesh m;
    std::vector<std::string> tok;
    {
        LineReader in(node_path, '#');
        if (!in.next(tok)) in.fail_eof("expected the header '<#points> 3 <#attributes> <boundary markers>'");
        const long n = in.integer(tok[0]);
        if (n <= 0) in.fail("number of points must be > 0, got " + tok[0]);
        if (tok.size() > 1 && in.integer(tok[1]) != 3) in.fail("dimension must be 3, got " + tok[1]);
        for (long i = 0; i < n; ++i) {
            if (!in.next(tok)) in.fail_eof("expected " + std::to_string(n) + " points, got " + std::to_string(i));
            if (tok.size() < 4) in.fail("expected '<id> x y z', got '" + in.text() + "'");
            m.node_ids.push_back(in.integer(tok[0]));
            m.nodes.emplace_back(in.real(tok[1]), in.real(tok[2]), in.real(tok[3]));
        }
    }
    {
        LineReader in(ele_path, '#');
        if (!in.next(tok)) in.fail_eof("expected the header '<#tets> <nodes per tet> <#attributes>'");
        const long n = in.integer(tok[0]);
        if (n <= 0) in.fail("number of tets must be > 0, got " + tok[0]);
        if (tok.size() > 1 && in.integer(tok[1]) != 4)
            in.fail("only 4-node tets are supported, got " + tok[1] + " nodes per tet");
        for (long i = 0; i < n; ++i) {
            if (!in.next(tok)) in.fail_eof("expected " + std::to_string(n) + " tets, got " + std::to_string(i));
            if (tok.size() < 5) in.fail("expected '<id> n1 n2 n3 n4', got '" + in.text() + "'");
            m.tets.push_back({in.integer(tok[1]), in.integer(tok[2]), in.integer(tok[3]), in.integer(tok[4])});
            m.tet_lines.push_back(in.line());
        }
    }
    return m.finish(ele_path);
}

TetMesh read_gmsh(const std::string& path)
{
    LineReader in(path, 0);
    IdMesh m;
    std::vector<std::string> tok;
    double version = 0;
    auto expect_end = [&](const std::string& end) {
        if (!in.next(tok)) in.fail_eof("expected " + end);
        if (tok[0] != end) in.fail("expected " + end + ", got '" + in.text() + "'");
    };
    while (in.next(tok)) {
        const std::string& key = tok[0];
        if (key == "$MeshFormat") {
            if (!in.next(tok)) in.fail_eof("expected 'version file-type data-size'");
            version = in.real(tok[0]);
            if (tok.size() < 2 || tok[1] != "0")
                in.fail("only ASCII .msh files are supported (file-type 0), got '" + in.text() + "'");
            if (version != 2.2 && !(version >= 4.0 && version < 4.2))
                in.fail("unsupported .msh version " + tok[0] + " (2.2 and 4.1 are read)");
            expect_end("$EndMeshFormat");
        } else if (key == "$Nodes") {
            if (version == 0) in.fail("$Nodes before $MeshFormat");
            if (!in.next(tok)) in.fail_eof("node count");
            if (version < 3) {
                const long n = in.integer(tok[0]);
                for (long i = 0; i < n; ++i) {
                    if (!in.next(tok) || tok.size() < 4) in.fail("expected 'id x y z', got '" + in.text() + "'");
                    m.node_ids.push_back(in.integer(tok[0]));
                    m.nodes.emplace_back(in.real(tok[1]), in.real(tok[2]), in.real(tok[3]));
                }
            } else {
                if (tok.size() < 2) in.fail("expected 'numEntityBlocks numNodes minTag maxTag'");
                const long blocks = in.integer(tok[0]);
                for (long b = 0; b < blocks; ++b) {
                    if (!in.next(tok) || tok.size() < 4)
                        in.fail("expected 'entityDim entityTag parametric numNodesInBlock', got '" + in.text() + "'");
                    if (in.integer(tok[2]) != 0) in.fail("parametric nodes are not supported");
                    const long n = in.integer(tok[3]);
                    const size_t first = m.node_ids.size();
                    for (long i = 0; i < n; ++i) {
                        if (!in.next(tok)) in.fail_eof("node tag");
                        m.node_ids.push_back(in.integer(tok[0]));
                    }
                    for (long i = 0; i < n; ++i) {
                        if (!in.next(tok) || tok.size() < 3) in.fail("expected 'x y z', got '" + in.text() + "'");
                        m.nodes.emplace_back(in.real(tok[0]), in.real(tok[1]), in.real(tok[2]));
                    }
                    (void)first;
                }
            }
            expect_end("$EndNodes");
        } else if (key == "$Elements") {
            if (version == 0) in.fail("$Elements before $MeshFormat");
            if (!in.next(tok)) in.fail_eof("element count");
            if (version < 3) {
                const long n = in.integer(tok[0]);
                for (long i = 0; i < n; ++i) {
                    if (!in.next(tok) || tok.size() < 3)
                        in.fail("expected 'id type ntags ...', got '" + in.text() + "'");
                    const long type = in.integer(tok[1]), ntags = in.integer(tok[2]);
                    if (type != 4) continue;  // only 4-node tets; points, lines, triangles are skipped
                    if (static_cast<long>(tok.size()) != 3 + ntags + 4)
                        in.fail("tet element needs 4 node ids after " + std::to_string(ntags) + " tags, got '" +
                                in.text() + "'");
                    const size_t o = static_cast<size_t>(3 + ntags);
                    m.tets.push_back(
                        {in.integer(tok[o]), in.integer(tok[o + 1]), in.integer(tok[o + 2]), in.integer(tok[o + 3])});
                    m.tet_lines.push_back(in.line());
                }
            } else {
                const long blocks = in.integer(tok[0]);
                for (long b = 0; b < blocks; ++b) {
                    if (!in.next(tok) || tok.size() < 4)
                        in.fail("expected 'entityDim entityTag elementType numElementsInBlock', got '" + in.text() +
                                "'");
                    const long type = in.integer(tok[2]), n = in.integer(tok[3]);
                    for (long i = 0; i < n; ++i) {
                        if (!in.next(tok)) in.fail_eof("element");
                        if (type != 4) continue;
                        if (tok.size() != 5) in.fail("expected 'tag n1 n2 n3 n4', got '" + in.text() + "'");
                        m.tets.push_back(
                            {in.integer(tok[1]), in.integer(tok[2]), in.integer(tok[3]), in.integer(tok[4])});
                        m.tet_lines.push_back(in.line());
                    }
                }
            }
            expect_end("$EndElements");
        } else if (key[0] == '$' && key.rfind("$End", 0) != 0) {
            const std::string end = "$End" + key.substr(1);  // skip unknown sections
            while (in.next(tok) && tok[0] != end) {}
        } else
            in.fail("unexpected '" + in.text() + "'");
    }
    if (version == 0) throw_input_error(path, "", "no $MeshFormat section: not a Gmsh .msh file");
    return m.finish(path);
}

TetMesh read_medit(const std::string& path)
{
    LineReader in(path, '#');
    IdMesh m;
    std::vector<std::string> tok;
    auto count_after = [&](std::vector<std::string>& t) {
        if (t.size() >= 2) return in.integer(t[1]);
        if (!in.next(t)) in.fail_eof("expected a count");
        return in.integer(t[0]);
    };
    while (in.next(tok)) {
        const std::string key = lower(tok[0]);
        if (key == "meshversionformatted" || key == "meshversion") {
            if (tok.size() < 2 && !in.next(tok)) in.fail_eof("version");
        } else if (key == "dimension") {
            const long d = count_after(tok);
            if (d != 3) in.fail("dimension must be 3, got " + std::to_string(d));
        } else if (key == "vertices") {
            const long n = count_after(tok);
            for (long i = 0; i < n; ++i) {
                if (!in.next(tok)) in.fail_eof("vertex " + std::to_string(i + 1) + " of " + std::to_string(n));
                if (tok.size() < 3) in.fail("expected 'x y z ref', got '" + in.text() + "'");
                m.node_ids.push_back(i + 1);
                m.nodes.emplace_back(in.real(tok[0]), in.real(tok[1]), in.real(tok[2]));
            }
        } else if (key == "tetrahedra") {
            const long n = count_after(tok);
            for (long i = 0; i < n; ++i) {
                if (!in.next(tok)) in.fail_eof("tet " + std::to_string(i + 1) + " of " + std::to_string(n));
                if (tok.size() < 4) in.fail("expected 'n1 n2 n3 n4 ref', got '" + in.text() + "'");
                m.tets.push_back({in.integer(tok[0]), in.integer(tok[1]), in.integer(tok[2]), in.integer(tok[3])});
                m.tet_lines.push_back(in.line());
            }
        } else if (key == "end")
            break;
        else {
            // Other sections (Triangles, Edges, Corners, ...): "<Keyword> n" then n lines.
            if (std::isdigit(static_cast<unsigned char>(tok[0][0])) || tok[0][0] == '-')
                in.fail("unexpected data line '" + in.text() + "' outside a section");
            const long n = count_after(tok);
            for (long i = 0; i < n; ++i)
                if (!in.next(tok)) in.fail_eof("section " + key);
        }
    }
    return m.finish(path);
}

TetMesh read_tet_mesh(const std::string& path)
{
    const std::string ext = extension(path);
    if (ext == ".abq" || ext == ".inp") return read_abq(path);
    if (ext == ".node" || ext == ".ele") return read_tetgen(path);
    if (ext == ".msh") return read_gmsh(path);
    if (ext == ".mesh") return read_medit(path);
    throw_input_error(path, "", "unknown tet mesh extension '" + ext + "' (expected .abq .inp .node .ele .msh .mesh)");
}

namespace {
void add_polygon(LineReader& in, std::vector<std::array<int, 3>>& faces, const std::vector<long>& ids, long nv)
{
    if (ids.size() < 3) in.fail("a face needs at least 3 vertices, got " + std::to_string(ids.size()));
    for (long id : ids)
        if (id < 0 || id >= nv)
            in.fail("vertex index " + std::to_string(id) + " out of range (" + std::to_string(nv) + " vertices)");
    for (size_t k = 1; k + 1 < ids.size(); ++k)
        faces.push_back({static_cast<int>(ids[0]), static_cast<int>(ids[k]), static_cast<int>(ids[k + 1])});
}

SurfaceMesh to_surface(const std::vector<Vec3>& v, const std::vector<std::array<int, 3>>& f, const std::string& path)
{
    if (v.empty()) throw_input_error(path, "", "no vertices found");
    if (f.empty()) throw_input_error(path, "", "no faces found");
    SurfaceMesh s;
    s.positions.resize(static_cast<Eigen::Index>(v.size()), 3);
    for (size_t i = 0; i < v.size(); ++i) s.positions.row(static_cast<Eigen::Index>(i)) = v[i].transpose();
    s.faces.resize(static_cast<Eigen::Index>(f.size()), 3);
    for (size_t i = 0; i < f.size(); ++i)
        for (int k = 0; k < 3; ++k) s.faces(static_cast<Eigen::Index>(i), k) = f[i][k];
    return s;
}
}  // namespace

SurfaceMesh read_off(const std::string& path)
{
    LineReader in(path, '#');
    std::vector<std::string> tok;
    if (!in.next(tok)) in.fail_eof("expected the header 'OFF' or 'COFF'");
    std::string head = tok[0];
    // Accept OFF, COFF, NOFF, CNOFF ... (colour and normal columns after x y z are ignored).
    if (head.size() < 3 || head.substr(head.size() - 3) != "OFF")
        in.fail("expected the header 'OFF' or 'COFF', got '" + in.text() + "'");
    tok.erase(tok.begin());
    if (tok.empty() && !in.next(tok)) in.fail_eof("expected '<#vertices> <#faces> <#edges>'");
    if (tok.size() < 2) in.fail("expected '<#vertices> <#faces> <#edges>', got '" + in.text() + "'");
    const long nv = in.integer(tok[0]), nf = in.integer(tok[1]);
    if (nv <= 0 || nf <= 0) in.fail("vertex and face counts must be > 0, got '" + in.text() + "'");
    std::vector<Vec3> v;
    // The count is a declaration, not memory present: grow with the vertices actually read (a
    // 30-byte file declaring 2e9 vertices once reserved 48 GB).
    v.reserve(static_cast<size_t>(std::min(nv, 1L << 16)));
    for (long i = 0; i < nv; ++i) {
        if (!in.next(tok)) in.fail_eof("expected " + std::to_string(nv) + " vertices, got " + std::to_string(i));
        if (tok.size() < 3) in.fail("expected 'x y z', got '" + in.text() + "'");
        v.emplace_back(in.real(tok[0]), in.real(tok[1]), in.real(tok[2]));
    }
    std::vector<std::array<int, 3>> f;
    std::vector<long> ids;
    for (long i = 0; i < nf; ++i) {
        if (!in.next(tok)) in.fail_eof("expected " + std::to_string(nf) + " faces, got " + std::to_string(i));
        const long k = in.integer(tok[0]);
        if (k < 3 || static_cast<long>(tok.size()) < 1 + k)
            in.fail("expected '<k> i1 .. ik' with k >= 3, got '" + in.text() + "'");
        ids.clear();
        for (long j = 0; j < k; ++j) ids.push_back(in.integer(tok[static_cast<size_t>(1 + j)]));
        add_polygon(in, f, ids, nv);
    }
    return to_surface(v, f, path);
}

SurfaceMesh read_obj(const std::string& path)
{
    LineReader in(path, '#');
    std::vector<std::string> tok;
    std::vector<Vec3> v;
    std::vector<std::array<int, 3>> f;
    std::vector<long> ids;
    while (in.next(tok)) {
        if (tok[0] == "v") {
            if (tok.size() < 4) in.fail("expected 'v x y z', got '" + in.text() + "'");
            v.emplace_back(in.real(tok[1]), in.real(tok[2]), in.real(tok[3]));
        } else if (tok[0] == "f") {
            ids.clear();
            for (size_t j = 1; j < tok.size(); ++j) {
                const std::string first = tok[j].substr(0, tok[j].find('/'));  // "i/t/n" -> i
                long id = in.integer(first);
                if (id == 0) in.fail("OBJ vertex indices start at 1, got 0");
                id = id > 0 ? id - 1 : static_cast<long>(v.size()) + id;  // negative: relative
                ids.push_back(id);
            }
            add_polygon(in, f, ids, static_cast<long>(v.size()));
        }
        // vt, vn, o, g, s, usemtl, mtllib: not needed
    }
    return to_surface(v, f, path);
}

SurfaceMesh read_surface_mesh(const std::string& path)
{
    const std::string ext = extension(path);
    if (ext == ".off") return read_off(path);
    if (ext == ".obj") return read_obj(path);
    throw_input_error(path, "", "unknown surface mesh extension '" + ext + "' (expected .off or .obj)");
}

bool is_surface_mesh_path(const std::string& path)
{
    const std::string ext = extension(path);
    return ext == ".off" || ext == ".obj";
}

void write_obj(const std::string& path, const SurfaceMesh& mesh)
{
    std::string text;
    char line[128];
    std::snprintf(line, sizeof line, "# contactbench surface, %ld vertices, %ld faces\n",
                  static_cast<long>(mesh.positions.rows()), static_cast<long>(mesh.faces.rows()));
    text += line;
    for (Eigen::Index i = 0; i < mesh.positions.rows(); ++i) {
        std::snprintf(line, sizeof line, "v %.9g %.9g %.9g\n", mesh.positions(i, 0), mesh.positions(i, 1),
                      mesh.positions(i, 2));
        text += line;
    }
    for (Eigen::Index i = 0; i < mesh.faces.rows(); ++i) {
        std::snprintf(line, sizeof line, "f %d %d %d\n", mesh.faces(i, 0) + 1, mesh.faces(i, 1) + 1,
                      mesh.faces(i, 2) + 1);
        text += line;
    }
    write_file_atomic(path, text);  // checked writes, fsync, rename: no partial frame after a crash
}

}  // namespace cb::sim
