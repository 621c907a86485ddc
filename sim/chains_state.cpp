#include "sim/chains_state.hpp"

#include "problems/io_util.hpp"

#include <cstring>
#include <filesystem>

namespace cb::sim {

namespace {
constexpr const char* MAGIC = "cb-chains-resume 1\n";

void put(std::string& out, const Vec& v) { out.append(reinterpret_cast<const char*>(v.data()), 8 * size_t(v.size())); }

std::vector<long> sizes(const std::vector<Vec>& vs)
{
    std::vector<long> n;
    for (const Vec& v : vs) n.push_back(static_cast<long>(v.size()));
    return n;
}
}  // namespace

std::string chains_state_path(const std::string& out_dir) { return out_dir + "/chains.state"; }

void write_chains_state(const std::string& out_dir, const ChainsState& s)
{
    // Doubles in the header are written by nlohmann's shortest round-trip form: read back exactly.
    const nlohmann::json head = {{"identity", s.identity},
                                 {"frames_done", s.frames_done},
                                 {"csv_bytes", s.csv_bytes},
                                 {"steps_done", s.steps_done},
                                 {"stopped", s.stopped},
                                 {"x", sizes(s.x)},
                                 {"v", sizes(s.v)},
                                 {"eigenvector", sizes(s.eigenvector)},
                                 {"difference", {s.difference.frame, s.difference.value, sizes(s.difference.x)}},
                                 {"penetration", {s.penetration.frame, s.penetration.value, sizes(s.penetration.x)}}};
    std::string out = MAGIC + head.dump() + "\n";
    for (const auto* vs : {&s.x, &s.v, &s.eigenvector, &s.difference.x, &s.penetration.x})
        for (const Vec& v : *vs) put(out, v);
    write_file_atomic(chains_state_path(out_dir), out);
}

std::optional<ChainsState> read_chains_state(const std::string& out_dir)
{
    const std::string path = chains_state_path(out_dir);
    std::error_code ec;
    if (!std::filesystem::exists(std::filesystem::symlink_status(path, ec))) return std::nullopt;
    const std::string text = read_regular_file(path);
    const size_t magic = std::strlen(MAGIC);
    const size_t eol = text.find('\n', magic);
    if (text.compare(0, magic, MAGIC) != 0 || eol == std::string::npos)
        throw_input_error(path, "", "not a chains resume state of this version (--fresh discards it)");
    const nlohmann::json head = parse_json_text(text.substr(magic, eol - magic), path);
    ChainsState s;
    try {
        s.identity = head.at("identity");
        s.frames_done = head.at("frames_done").get<long>();
        s.csv_bytes = head.at("csv_bytes").get<long>();
        s.steps_done = head.at("steps_done").get<std::vector<long>>();
        s.stopped = head.at("stopped").get<std::vector<bool>>();
        const auto picture = [&head](const char* key, PicturedFrame& p) {
            const nlohmann::json& j = head.at(key);
            p.frame = j.at(0).get<long>();
            p.value = j.at(1).get<double>();
            return j.at(2).get<std::vector<long>>();
        };
        const std::vector<std::vector<long>> n = {
            head.at("x").get<std::vector<long>>(), head.at("v").get<std::vector<long>>(),
            head.at("eigenvector").get<std::vector<long>>(), picture("difference", s.difference),
            picture("penetration", s.penetration)};
        size_t need = 0;
        for (const auto& list : n)
            for (long size : list) {
                if (size < 0) throw_input_error(path, "", "damaged (--fresh discards it)");
                need += 8 * size_t(size);
            }
        if (text.size() - eol - 1 != need) throw_input_error(path, "", "truncated or damaged (--fresh discards it)");
        const char* p = text.data() + eol + 1;
        std::vector<Vec>* into[] = {&s.x, &s.v, &s.eigenvector, &s.difference.x, &s.penetration.x};
        for (size_t k = 0; k < n.size(); ++k)
            for (long size : n[k]) {
                Vec v(size);
                std::memcpy(v.data(), p, 8 * size_t(size));
                p += 8 * size_t(size);
                into[k]->push_back(std::move(v));
            }
    } catch (const nlohmann::json::exception& e) {
        throw_input_error(path, "", std::string("damaged header: ") + e.what() + " (--fresh discards it)");
    }
    return s;
}

}  // namespace cb::sim
