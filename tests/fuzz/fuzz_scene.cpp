// libFuzzer entry point for the scene reader (sim/scene.hpp) on in-memory bytes: a scene
// must either load (meshes built, bodies placed) or be rejected with an InputError. A crash, a
// sanitizer report, a hang, an out-of-memory or any other exception is a bug in the reader.
// Scenes are capped at 20000 tets here (PathRoots::max_tets) so that each input stays fast; the
// bound itself is what keeps `box.cells` 3e9 from allocating.
// Build: cmake -DCB_FUZZ=ON with CXX=clang++ (target fuzz_scene), see tests/fuzz/README.md.
#include "problems/io_util.hpp"
#include "sim/scene.hpp"
#include "solvers/core/types.hpp"

#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    const std::string text(reinterpret_cast<const char*>(data), size);
    cb::sim::PathRoots roots;
    roots.scene_dir = "/nonexistent-fuzz-scene-dir";  // relative mesh paths resolve nowhere
    roots.cache = "/nonexistent-fuzz-cache";
    roots.max_tets = 20000;
    try {
        const nlohmann::json j = cb::parse_json_text(text, "fuzz-scene.json", /*allow_comments=*/true);
        const cb::sim::Scene scene = cb::sim::load_scene_json(j, "fuzz-scene.json", roots);
        long tets = 0;
        for (const auto& b : scene.bodies) tets += b.mesh.tet_count();
        if (scene.bodies.empty() || tets > roots.max_tets) __builtin_trap();  // the bound held
    } catch (const cb::InputError&) {
        // the expected rejection of a bad scene
    }
    return 0;
}
