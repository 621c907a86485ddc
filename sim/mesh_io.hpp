#pragma once
/// Mesh readers and writers. Tet meshes: Abaqus .abq (C3D4), TetGen .node/.ele, Gmsh .msh
/// (2.2 and 4.1 ASCII), Medit .mesh. Surfaces: OFF (also COFF with colour columns, polygons
/// fan-triangulated) and OBJ. Every error names the file, the line and what is wrong:
/// "dino.abq: line 1307: expected 5 integers 'id,n1,n2,n3,n4', got '12,4,5'".
#include "sim/tet_mesh.hpp"

#include <string>

namespace cb::sim {

TetMesh read_abq(const std::string& path);
/// `path` is either the .node or the .ele file; the other is found beside it.
TetMesh read_tetgen(const std::string& path);
TetMesh read_gmsh(const std::string& path);
TetMesh read_medit(const std::string& path);
/// Dispatches on the extension (.abq .inp .node .ele .msh .mesh); tets are oriented positively.
TetMesh read_tet_mesh(const std::string& path);

SurfaceMesh read_off(const std::string& path);
SurfaceMesh read_obj(const std::string& path);
/// Dispatches on the extension (.off .obj).
SurfaceMesh read_surface_mesh(const std::string& path);

/// True when the extension names a surface format (.off .obj).
bool is_surface_mesh_path(const std::string& path);

/// Writes a triangle surface as Wavefront OBJ (atomic: temporary file, then rename).
void write_obj(const std::string& path, const SurfaceMesh& mesh);

}  // namespace cb::sim
