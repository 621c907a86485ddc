#include "sim/state_file.hpp"

#include "problems/io_util.hpp"

#include <cstring>
#include <filesystem>

namespace cb::sim {

void write_state_file(const std::string& path, const char* magic, const nlohmann::json& head,
                      const std::vector<const Vec*>& vectors)
{
    std::string out = magic + head.dump() + "\n";
    for (const Vec* v : vectors) out.append(reinterpret_cast<const char*>(v->data()), 8 * size_t(v->size()));
    write_file_atomic(path, out);
}

std::optional<StateFile> read_state_file(const std::string& path, const char* magic, const std::string& what)
{
    std::error_code ec;
    if (!std::filesystem::exists(std::filesystem::symlink_status(path, ec))) return std::nullopt;
    const std::string text = read_regular_file(path);
    const size_t magic_size = std::strlen(magic);
    const size_t eol = text.find('\n', magic_size);
    if (text.compare(0, magic_size, magic) != 0 || eol == std::string::npos)
        throw_input_error(path, "", "not " + what + " of this version (--fresh discards it)");
    StateFile file;
    file.path = path;
    file.head = parse_json_text(text.substr(magic_size, eol - magic_size), path);
    file.body = text.substr(eol + 1);
    return file;
}

std::vector<Vec> StateFile::vectors(const std::vector<long>& sizes) const
{
    size_t need = 0;
    for (long size : sizes) {
        if (size < 0 || size_t(size) > body.size() / 8) throw_input_error(path, "", "damaged (--fresh discards it)");
        need += 8 * size_t(size);
    }
    if (body.size() != need) throw_input_error(path, "", "truncated or damaged (--fresh discards it)");
    std::vector<Vec> out;
    out.reserve(sizes.size());
    const char* p = body.data();
    for (long size : sizes) {
        Vec v(size);
        std::memcpy(v.data(), p, 8 * size_t(size));
        p += 8 * size_t(size);
        out.push_back(std::move(v));
    }
    return out;
}

}  // namespace cb::sim
