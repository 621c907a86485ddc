// A results folder judged whole: finished, unlocked, one final record per job.
#include "harness/results_folder.hpp"

#include "harness/record_types.hpp"
#include "harness/results.hpp"
#include "problems/io_util.hpp"
#include "solvers/core/types.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <map>
#include <set>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

namespace cb {

namespace fs = std::filesystem;

namespace {

/// The pid a lock holder wrote into DIR/.lock, its first word ("?" when unreadable).
std::string holder_pid(int fd)
{
    char holder[32] = {0};
    const ssize_t got = ::pread(fd, holder, sizeof holder - 1, 0);
    const std::string text = got > 0 ? std::string(holder, size_t(got)) : std::string();
    const std::string pid = text.substr(0, text.find_first_of(" \n"));  // "<pid> <command>\n" (run_lock.cpp)
    return pid.empty() ? std::string("?") : pid;
}

/// lstat without following: true when something (a file, a link, a FIFO) is at `path`.
bool present(const fs::path& path)
{
    struct stat st {};
    return ::lstat(path.c_str(), &st) == 0;
}

}  // namespace

void require_unlocked(const std::string& dir)
{
    const std::string path = (fs::path(dir) / ".lock").string();
    const int fd = ::open(path.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) return;  // no lock file: no run has held it
    struct stat st {};
    if (::fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && ::flock(fd, LOCK_SH | LOCK_NB) != 0 && errno == EWOULDBLOCK) {
        const std::string pid = holder_pid(fd);
        ::close(fd);
        throw_input_error(dir, "",
                          "being written by `contactbench run` (pid " + pid +
                              ", holding .lock): not a finished result; wait for it to finish");
    }
    ::close(fd);
}

void check_run_record(const nlohmann::json& record, const std::string& path, const std::string& file_name)
{
    if (!record.is_object()) throw_input_error(path, "", "expected a run record (a JSON object)");
    const auto snapshot = record.find("snapshot");
    if (snapshot == record.end() || !snapshot->is_object() || !snapshot->contains("id") ||
        !(*snapshot)["id"].is_string())
        throw_input_error(path, "/snapshot/id", "missing or not a string: not a run record of `contactbench run`");
    const auto label = record.find("label");
    if (label == record.end() || !label->is_string())
        throw_input_error(path, "/label", "missing or not a string: not a run record of `contactbench run`");
    const std::string expected = run_file_name((*snapshot)["id"].get<std::string>(), label->get<std::string>());
    if (expected != file_name)
        throw_input_error(path, "/snapshot/id, /label",
                          "the record is of job " + expected +
                              ", not of this file: a copy or another job's record (remove it, or run again)");
    check_record_file_types(record, path);  // counters, times and accuracy of the types their readers take
    const auto final = record.find("final");
    if (final != record.end() && !final->is_boolean())
        throw_input_error(path, "/final", "expected true or false, got " + final->dump());
    if (final != record.end() && !final->get<bool>())
        throw_input_error(path, "/final",
                          "false: the run ended in an error to be retried, not a result (run the suite again)");
}

std::vector<nlohmann::json> read_finished_runs(const std::string& dir)
{
    require_unlocked(dir);
    const fs::path root(dir);
    if (present(root / "suite.pending.json"))
        throw_input_error(dir, "suite.pending.json",
                          "present: the folder's `contactbench run` was interrupted or is still running, so its "
                          "results are incomplete (run it again to finish)");
    const bool has_jobs = present(root / "jobs.json");  // older folders have none: read as bare
    const fs::path runs = root / "runs";
    std::error_code ec;
    std::vector<std::string> files;
    if (fs::is_directory(fs::symlink_status(runs, ec))) {
        for (fs::directory_iterator it(runs, ec), end; !ec && it != end; it.increment(ec))
            if (it->path().extension() == ".json") files.push_back(it->path().filename().string());
        if (ec) throw_input_error(runs.string(), "", "cannot list the folder: " + ec.message());
    } else if (present(runs)) {
        throw_input_error(runs.string(), "", "not a folder (a link or a special file): not a results folder");
    }
    std::sort(files.begin(), files.end());
    if (has_jobs) {
        const std::string jobs_path = (root / "jobs.json").string();
        const nlohmann::json jobs = read_json_file(jobs_path);
        if (!jobs.is_object() || !jobs.contains("jobs") || !jobs["jobs"].is_array())
            throw_input_error(jobs_path, "/jobs", "missing or not a list of run files");
        if (jobs.contains("complete") && jobs["complete"] != true)
            throw_input_error(jobs_path, "/complete",
                              jobs["complete"].dump() + ": some jobs have no run file (run the suite again)");
        std::set<std::string> listed;
        for (const auto& f : jobs["jobs"]) {
            if (!f.is_string()) throw_input_error(jobs_path, "/jobs", "expected run file names, got " + f.dump());
            listed.insert(f.get<std::string>());
        }
        for (const auto& f : files)
            if (!listed.count(f))
                throw_input_error((runs / f).string(), "",
                                  "not a job of " + jobs_path + ": a stray or stale file (remove it, or run again)");
        for (const auto& f : listed)
            if (!std::binary_search(files.begin(), files.end(), f))
                throw_input_error((runs / f).string(), "", "missing: the results are incomplete (run the suite again)");
    }
    // A folder of `run` (suite.json or jobs.json): each file is its job's. A bare folder of run
    // files (by hand, or `stress --out`, whose file names carry the solver spec): one record per
    // (snapshot, label) still, since compare pairs runs by that key.
    const bool run_folder = has_jobs;
    std::map<std::pair<std::string, std::string>, std::string> file_of_key;
    std::vector<nlohmann::json> out;
    for (const auto& f : files) {
        const std::string path = (runs / f).string();
        nlohmann::json run = read_json_file(path);  // a FIFO, device or link loop: refused by name
        if (run_folder) {
            check_run_record(run, path, f);
        } else {
            if (!run.is_object()) throw_input_error(path, "", "expected a run record (a JSON object)");
            const auto snapshot = run.find("snapshot");
            const std::string id = snapshot != run.end() && snapshot->is_object() && snapshot->contains("id") &&
                                           (*snapshot)["id"].is_string()
                                       ? (*snapshot)["id"].get<std::string>()
                                       : "";
            const auto label = run.find("label");
            const std::string name = label != run.end() && label->is_string() ? label->get<std::string>() : "";
            const auto [other, fresh] = file_of_key.emplace(std::make_pair(id, name), f);
            if (!fresh)
                throw_input_error(path, "/snapshot/id, /label",
                                  "the same job (" + id + ", " + name + ") as " + other->second +
                                      ": one record per job (remove the stale one)");
        }
        run["_file"] = f;
        out.push_back(std::move(run));
    }
    return out;
}

}  // namespace cb
