// Suite entries that name a simulation folder: {"sim": DIR, "frames": "3:8", "stride": 1,
// "min_rows": 20} picks snapshots from DIR/steps.csv (docs/INTERFACES.md "Suite JSON").
#include "harness/suite.hpp"

#include "solvers/core/types.hpp"

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

namespace cb {

namespace fs = std::filesystem;

namespace {

long parse_frame(const std::string& text, const std::string& at, const std::string& whole)
{
    try {
        size_t used = 0;
        const long v = std::stol(text, &used);
        if (used == text.size() && v >= 0) return v;
    } catch (const std::exception&) {
    }
    throw_input_error(at, "/frames",
                      "expected \"a:b\", \"a:\", \":b\" or \"a\" with frames >= 0, got \"" + whole + "\"");
}

long non_negative(const nlohmann::json& e, const char* key, const std::string& at, long fallback, long min)
{
    if (!e.contains(key)) return fallback;
    if (!e[key].is_number_integer() || e[key].get<long>() < min)
        throw_input_error(at, std::string("/") + key,
                          "expected an integer >= " + std::to_string(min) + ", got " + e[key].dump());
    return e[key].get<long>();
}

std::vector<std::string> split(const std::string& line, char sep)
{
    std::vector<std::string> out;
    std::string cell;
    std::istringstream in(line);
    while (std::getline(in, cell, sep)) out.push_back(cell);
    if (!line.empty() && line.back() == sep) out.emplace_back();
    return out;
}

/// The command that writes the simulation folder, for error messages: paths as seen from the
/// working directory (the suite's are relative to the suite file), so that it can be pasted.
std::string simulate_command(const SuiteSimulation& sim, const fs::path& base, const fs::path& folder,
                             long frames_needed)
{
    std::string scene = "SCENE.json";
    if (!sim.scene.empty())
        scene = fs::path(sim.scene).is_absolute() ? sim.scene : (base / sim.scene).lexically_normal().string();
    std::string cmd = "contactbench simulate " + scene + " --out " + folder.lexically_normal().string();
    if (frames_needed > 0) cmd += " --frames " + std::to_string(frames_needed);
    return cmd;
}

}  // namespace

SuiteSimulation parse_suite_simulation(const nlohmann::json& e, const std::string& at)
{
    for (const auto& item : e.items())
        if (item.key() != "sim" && item.key() != "frames" && item.key() != "stride" && item.key() != "min_rows" &&
            item.key() != "newton" && item.key() != "scene")
            throw_input_error(at, "/" + item.key(), "unknown key; known: frames, min_rows, newton, scene, sim, stride");
    SuiteSimulation s;
    if (!e.contains("sim") || !e["sim"].is_string() || e["sim"].get<std::string>().empty())
        throw_input_error(at, "/sim",
                          "expected the folder of a simulation (contactbench simulate --out DIR), got " +
                              (e.contains("sim") ? e["sim"].dump() : std::string("nothing")));
    s.folder = e["sim"].get<std::string>();
    if (e.contains("frames")) {
        const auto& f = e["frames"];
        if (f.is_number_integer() && f.get<long>() >= 0) {
            s.first = f.get<long>();
            s.end = s.first + 1;
        } else if (f.is_string()) {
            const std::string text = f.get<std::string>();
            const auto colon = text.find(':');
            if (colon == std::string::npos) {
                s.first = parse_frame(text, at, text);
                s.end = s.first + 1;
            } else {
                const std::string a = text.substr(0, colon), b = text.substr(colon + 1);
                s.first = a.empty() ? 0 : parse_frame(a, at, text);
                s.end = b.empty() ? -1 : parse_frame(b, at, text);
                if (s.end >= 0 && s.end <= s.first)
                    throw_input_error(at, "/frames", "\"" + text + "\" selects no frame (a:b means frames a to b-1)");
            }
        } else {
            throw_input_error(at, "/frames", "expected \"a:b\", \"a:\", \":b\", \"a\" or an integer, got " + f.dump());
        }
    }
    s.stride = non_negative(e, "stride", at, 1, 1);
    s.min_rows = non_negative(e, "min_rows", at, 0, 0);
    s.newton = non_negative(e, "newton", at, -1, 0);
    if (e.contains("scene")) {
        if (!e["scene"].is_string())
            throw_input_error(at, "/scene", "expected a scene file name, got " + e["scene"].dump());
        s.scene = e["scene"].get<std::string>();
    }
    return s;
}

std::vector<std::string> expand_suite_simulation(const SuiteSimulation& sim, const std::string& suite_path)
{
    const fs::path base = fs::path(suite_path).has_parent_path() ? fs::path(suite_path).parent_path() : fs::path(".");
    const fs::path folder =
        (fs::path(sim.folder).is_absolute() ? fs::path(sim.folder) : base / sim.folder).lexically_normal();
    const long frames_needed = sim.end >= 0 ? sim.end : 0;
    const fs::path steps_csv = folder / "steps.csv";
    if (!fs::is_regular_file(steps_csv))
        throw_input_error(suite_path, sim.field,
                          "no simulation in '" + folder.string() + "' (" +
                              (fs::is_directory(folder) ? "no steps.csv" : "no such folder") +
                              "); make it with: " + simulate_command(sim, base, folder, frames_needed));
    std::ifstream in(steps_csv);
    std::string line;
    std::getline(in, line);
    const std::vector<std::string> header = split(line, ',');
    std::map<std::string, size_t> col;
    for (size_t k = 0; k < header.size(); ++k) col[header[k]] = k;
    for (const char* need : {"frame", "newton_iteration", "rows", "snapshot"})
        if (!col.count(need))
            throw_input_error(steps_csv.string(), "",
                              std::string("no column '") + need + "' in the header '" + line + "'");

    // Frame -> its steps (a frame has one step per Newton iteration), in file order.
    struct Step {
        long frame, newton, rows;
        std::string snapshot;
    };
    std::vector<Step> steps;
    long last_frame = -1;
    for (long number = 2; std::getline(in, line); ++number) {
        if (line.empty()) continue;
        const std::vector<std::string> cells = split(line, ',');
        if (cells.size() != header.size())
            throw_input_error(steps_csv.string(), "line " + std::to_string(number),
                              "expected " + std::to_string(header.size()) + " cells, got " +
                                  std::to_string(cells.size()));
        try {
            steps.push_back({std::stol(cells[col["frame"]]), std::stol(cells[col["newton_iteration"]]),
                             std::stol(cells[col["rows"]]), cells[col["snapshot"]]});
        } catch (const std::exception&) {
            throw_input_error(steps_csv.string(), "line " + std::to_string(number),
                              "frame, newton_iteration and rows must be integers");
        }
        last_frame = std::max(last_frame, steps.back().frame);
    }
    if (sim.end > last_frame + 1)
        throw_input_error(suite_path, sim.field,
                          "frames up to " + std::to_string(sim.end - 1) + " asked, but '" + folder.string() +
                              "' holds frames 0.." + std::to_string(last_frame) +
                              "; make them with: " + simulate_command(sim, base, folder, frames_needed));

    std::vector<std::string> out;
    long selected = 0;  // index among the frames in range, for the stride
    long current = -1;
    bool keep_frame = false;
    for (const Step& st : steps) {
        if (st.frame != current) {
            current = st.frame;
            const bool in_range = st.frame >= sim.first && (sim.end < 0 || st.frame < sim.end);
            keep_frame = in_range && (selected % sim.stride == 0);
            if (in_range) ++selected;
        }
        if (!keep_frame || st.rows < sim.min_rows || (sim.newton >= 0 && st.newton != sim.newton)) continue;
        if (st.snapshot.empty())
            throw_input_error(suite_path, sim.field,
                              "frame " + std::to_string(st.frame) + " of '" + folder.string() +
                                  "' has no snapshot (simulated with --no-snapshots?); make it with: " +
                                  simulate_command(sim, base, folder, frames_needed));
        // The snapshot lives in the folder's snapshots/ whatever path steps.csv recorded.
        const fs::path file = folder / "snapshots" / fs::path(st.snapshot).filename();
        if (!fs::is_regular_file(file))
            throw_input_error(suite_path, sim.field,
                              "snapshot '" + file.string() +
                                  "' is missing; make it with: " + simulate_command(sim, base, folder, frames_needed));
        out.push_back(file.string());
    }
    if (out.empty())
        throw_input_error(suite_path, sim.field,
                          "selects no snapshot of '" + folder.string() + "' (frames 0.." + std::to_string(last_frame) +
                              ", min_rows " + std::to_string(sim.min_rows) + ")");
    return out;
}

}  // namespace cb
