#pragma once
/// Scene files (JSON): bodies, materials, obstacles, time stepping, detection, output.
/// Every key, its default and its unit are documented in scenes/README.md. Unknown keys are
/// errors naming the file and the JSON pointer ("scenes/x.json: /bodies/0/materal: unknown key").
#include "sim/collision/dcd.hpp"
#include "sim/collision/obstacles.hpp"
#include "sim/fem_corotated.hpp"
#include "sim/friction_step.hpp"
#include "sim/integrator.hpp"
#include "sim/tet_mesh.hpp"

#include <nlohmann/json.hpp>
#include <memory>
#include <string>
#include <vector>

namespace cb::sim {

/// Where "data:" and "cache:" mesh paths point.
struct PathRoots {
    std::string data;       ///< --data DIR (the authors' files); empty: "data:" paths unavailable
    std::string cache;      ///< $CB_CACHE or ~/.cache/contactbench
    std::string scene_dir;  ///< relative paths are relative to the scene file
    /// Bound on the scene's tets (every body, array copies included; a box cell is 6 tets):
    /// larger scenes are refused before their meshes are built (scenes/README.md "Limits").
    long max_tets = 6000000;
};
PathRoots default_path_roots(const std::string& scene_path, const std::string& data_dir);

/// One body after loading: its tet mesh already placed in the world, and where it came from.
struct Body {
    std::string name;
    TetMesh mesh;  ///< world rest positions
    Material material;
    Vec3 velocity = Vec3::Zero();  ///< m/s, initial
    std::string source;            ///< the mesh path actually used (or "box 16x16x32")
    std::string mesh_file;         ///< the mesh file read (empty for a box): an input of the simulation
    std::string quality;           ///< mesh quality report (tetrahedralised surfaces)
};

struct OutputSettings {
    bool snapshots = true;
    long snapshot_first = 0;  ///< frames [first, last] get snapshots (-1: to the end)
    long snapshot_last = -1;
    int strip_frames = 6;             ///< pictures in the PNG strip (0: none)
    int image_size = 256;             ///< pixels per picture (square)
    Vec3 view_deg = Vec3(20, 30, 0);  ///< camera: [pitch (down), yaw, roll] in degrees
    std::vector<long> export_frames;  ///< OBJ surfaces of these frames
};

struct Scene {
    std::string file;  ///< the scene file (for messages)
    std::string name;
    std::string description;
    StepParameters step;
    long frames = 20;
    int steps_per_frame = 1;
    int newton_iterations = 1;
    std::string solver = "mprgp";
    nlohmann::json solver_settings = nlohmann::json::object();
    bool allow_commands = false;  ///< the scene opts in to a `command` solver (external program)
    DetectionSettings detection;
    std::string detect_at = "start";  ///< "start" (the authors') or "predicted" (x + h v)
    double blowup_speed = 100.0;      ///< m/s: a faster vertex flags the frame as blown up
    FrictionSettings friction;        ///< "mu" and "friction_settings"; mu = 0: the frictionless QP step
    std::vector<Body> bodies;
    std::vector<std::unique_ptr<Obstacle>> obstacles;
    OutputSettings output;
};

/// Reads and validates a scene; loads (and, for surfaces, tetrahedralises) the meshes.
Scene load_scene(const std::string& path, const PathRoots& roots);
/// Same from JSON already in memory (`file` names it in messages).
Scene load_scene_json(const nlohmann::json& j, const std::string& file, const PathRoots& roots);

/// Converts one of the authors' .ini scene files (JSON syntax) into our scene JSON. Their
/// "alpha_k" multiplies M and "alpha_m" multiplies K (SOURCES.md), so alpha_k -> a_M and
/// alpha_m -> a_K. Mesh files "model/<name>.abq" map to "data:meshes/<mapped>".
nlohmann::json import_authors_ini(const nlohmann::json& ini, const std::string& file);

}  // namespace cb::sim
