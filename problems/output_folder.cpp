// What a command may write or delete in an output folder: see output_folder.hpp.
#include "problems/output_folder.hpp"

#include "solvers/core/types.hpp"  // throw_input_error

#include <filesystem>
#include <system_error>

namespace cb {

namespace fs = std::filesystem;

namespace {

const char* special_kind(fs::file_type type)
{
    switch (type) {
    case fs::file_type::symlink:
        return "is a symbolic link";
    case fs::file_type::fifo:
        return "is a FIFO";
    case fs::file_type::character:
        return "is a character device";
    case fs::file_type::block:
        return "is a block device";
    case fs::file_type::socket:
        return "is a socket";
    default:
        return nullptr;
    }
}

}  // namespace

void check_output_entry(const std::string& path, bool folder)
{
    std::error_code ec;
    const fs::file_status st = fs::symlink_status(path, ec);
    if (ec || st.type() == fs::file_type::not_found) return;
    if (const char* kind = special_kind(st.type()))
        throw_input_error(path, "",
                          std::string(kind) +
                              ": contactbench writes and deletes nothing through links or special files inside an "
                              "output folder; remove it or use another output folder");
    if (folder && st.type() != fs::file_type::directory)
        throw_input_error(path, "", "expected a folder; remove it or use another output folder");
    if (!folder && st.type() == fs::file_type::directory)
        throw_input_error(path, "", "is a folder: not replaced; remove it or use another output folder");
}

void make_output_folder(const std::string& folder)
{
    std::error_code ec;
    fs::create_directories(folder, ec);
    if (ec) throw_input_error(folder, "", "cannot create the output folder: " + ec.message());
    if (!fs::is_directory(folder, ec)) throw_input_error(folder, "", "not a folder");
}

std::string make_output_subfolder(const std::string& folder, const std::string& name)
{
    make_output_folder(folder);
    const std::string path = (fs::path(folder) / name).string();
    check_output_entry(path, /*folder=*/true);
    std::error_code ec;
    fs::create_directory(path, ec);
    if (ec) throw_input_error(path, "", "cannot create the folder: " + ec.message());
    check_output_entry(path, /*folder=*/true);  // made by us, or a real folder that was there
    return path;
}

void check_output_entries(const std::string& folder, const std::function<bool(const std::string&)>& select)
{
    std::error_code ec;
    if (fs::symlink_status(folder, ec).type() != fs::file_type::directory) return;
    for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec))
        if (select(it->path().filename().string())) check_output_entry(it->path().string());
}

}  // namespace cb
