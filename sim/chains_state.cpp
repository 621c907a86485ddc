#include "sim/chains_state.hpp"

#include "problems/io_util.hpp"
#include "sim/state_file.hpp"

namespace cb::sim {

namespace {
constexpr const char* MAGIC = "cb-chains-resume 1\n";

std::vector<long> sizes(const std::vector<Vec>& vs)
{
    std::vector<long> n;
    n.reserve(vs.size());
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
    std::vector<const Vec*> vectors;
    for (const auto* vs : {&s.x, &s.v, &s.eigenvector, &s.difference.x, &s.penetration.x})
        for (const Vec& v : *vs) vectors.push_back(&v);
    write_state_file(chains_state_path(out_dir), MAGIC, head, vectors);
}

std::optional<ChainsState> read_chains_state(const std::string& out_dir)
{
    const std::optional<StateFile> file = read_state_file(chains_state_path(out_dir), MAGIC, "a chains resume state");
    if (!file) return std::nullopt;
    const nlohmann::json& head = file->head;
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
        std::vector<long> sizes;
        for (const auto& list : n) sizes.insert(sizes.end(), list.begin(), list.end());
        std::vector<Vec> v = file->vectors(sizes);
        auto next = v.begin();
        std::vector<Vec>* into[] = {&s.x, &s.v, &s.eigenvector, &s.difference.x, &s.penetration.x};
        for (size_t k = 0; k < n.size(); ++k)
            for (size_t i = 0; i < n[k].size(); ++i) into[k]->push_back(std::move(*next++));
    } catch (const nlohmann::json::exception& e) {
        throw_input_error(file->path, "", std::string("damaged header: ") + e.what() + " (--fresh discards it)");
    }
    return s;
}

}  // namespace cb::sim
