#include "sim/resume_state.hpp"

#include "problems/io_util.hpp"
#include "sim/state_file.hpp"

#include <iterator>

namespace cb::sim {

namespace {
constexpr const char* MAGIC = "cb-resume 1\n";
}  // namespace

std::string resume_state_path(const std::string& out_dir) { return out_dir + "/resume.state"; }

void write_resume_state(const std::string& out_dir, const ResumeState& s)
{
    nlohmann::json head = {{"identity", s.identity},
                           {"frames_done", s.frames_done},
                           {"steps_done", s.steps_done},
                           {"finished", s.finished},
                           {"blow_up", s.blow_up},
                           {"peak_reset", s.peak_reset},
                           {"n", s.x.size()},
                           {"eigenvector", s.eigenvector.size()},
                           {"strip_frames", s.strip_frames}};
    std::vector<const Vec*> vectors = {&s.x, &s.v, &s.eigenvector};
    for (const Vec& x : s.strip_x) vectors.push_back(&x);
    write_state_file(resume_state_path(out_dir), MAGIC, head, vectors);
}

std::optional<ResumeState> read_resume_state(const std::string& out_dir)
{
    const std::optional<StateFile> file = read_state_file(resume_state_path(out_dir), MAGIC, "a resume state");
    if (!file) return std::nullopt;
    const nlohmann::json& head = file->head;
    ResumeState s;
    try {
        s.identity = head.at("identity");
        s.frames_done = head.at("frames_done").get<long>();
        s.steps_done = head.at("steps_done").get<long>();
        s.finished = head.at("finished").get<bool>();
        s.blow_up = head.at("blow_up").get<bool>();
        s.peak_reset = head.at("peak_reset").get<bool>();
        s.strip_frames = head.at("strip_frames").get<std::vector<long>>();
        const long n = head.at("n").get<long>(), ne = head.at("eigenvector").get<long>();
        std::vector<long> sizes = {n, n, ne};
        sizes.insert(sizes.end(), s.strip_frames.size(), n);
        std::vector<Vec> v = file->vectors(sizes);
        s.x = std::move(v[0]);
        s.v = std::move(v[1]);
        s.eigenvector = std::move(v[2]);
        s.strip_x.assign(std::make_move_iterator(v.begin() + 3), std::make_move_iterator(v.end()));
    } catch (const nlohmann::json::exception& e) {
        throw_input_error(file->path, "", std::string("damaged header: ") + e.what() + " (--fresh discards it)");
    }
    return s;
}

}  // namespace cb::sim
