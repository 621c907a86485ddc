#include "sim/resume_state.hpp"

#include "problems/io_util.hpp"

#include <cstring>
#include <filesystem>

namespace cb::sim {

namespace {
constexpr const char* MAGIC = "cb-resume 1\n";

void put(std::string& out, const Vec& v) { out.append(reinterpret_cast<const char*>(v.data()), 8 * size_t(v.size())); }
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
    std::string out = MAGIC + head.dump() + "\n";
    put(out, s.x);
    put(out, s.v);
    put(out, s.eigenvector);
    for (const Vec& x : s.strip_x) put(out, x);
    write_file_atomic(resume_state_path(out_dir), out);
}

std::optional<ResumeState> read_resume_state(const std::string& out_dir)
{
    const std::string path = resume_state_path(out_dir);
    std::error_code ec;
    if (!std::filesystem::exists(std::filesystem::symlink_status(path, ec))) return std::nullopt;
    const std::string text = read_regular_file(path);
    const size_t magic = std::strlen(MAGIC);
    const size_t eol = text.find('\n', magic);
    if (text.compare(0, magic, MAGIC) != 0 || eol == std::string::npos)
        throw_input_error(path, "", "not a resume state of this version (--fresh discards it)");
    const nlohmann::json head = parse_json_text(text.substr(magic, eol - magic), path);
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
        const size_t need = 8 * size_t(n) * (2 + s.strip_frames.size()) + 8 * size_t(ne);
        if (n < 0 || ne < 0 || text.size() - eol - 1 != need)
            throw_input_error(path, "", "truncated or damaged (--fresh discards it)");
        const char* p = text.data() + eol + 1;
        const auto take = [&p](long size) {
            Vec v(size);
            std::memcpy(v.data(), p, 8 * size_t(size));
            p += 8 * size_t(size);
            return v;
        };
        s.x = take(n);
        s.v = take(n);
        s.eigenvector = take(ne);
        for (size_t k = 0; k < s.strip_frames.size(); ++k) s.strip_x.push_back(take(n));
    } catch (const nlohmann::json::exception& e) {
        throw_input_error(path, "", std::string("damaged header: ") + e.what() + " (--fresh discards it)");
    }
    return s;
}

}  // namespace cb::sim
