// Runs plots/html_report.py: see html_report.hpp.
#include "harness/html_report.hpp"

#include "harness/program_run.hpp"
#include "harness/temp_folder.hpp"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#ifndef CB_SOURCE_DIR
#define CB_SOURCE_DIR "."
#endif

namespace cb {

namespace fs = std::filesystem;

namespace {

const char* const PYTHON = "/usr/bin/python3";

bool has_module(const fs::path& root)
{
    std::error_code ec;
    return fs::is_regular_file(root / "plots" / "html_report.py", ec);
}

std::string read_all(const fs::path& path)
{
    std::ifstream in(path);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

std::string trimmed(std::string text)
{
    while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
    return text;
}

}  // namespace

std::string plots_root()
{
    std::error_code ec;
    if (const char* env = std::getenv("CB_PLOTS_ROOT"); env && *env)
        return has_module(env) ? fs::absolute(env, ec).string() : "";
    for (const fs::path& root : {fs::path(CB_SOURCE_DIR), fs::current_path(ec)})
        if (!root.empty() && has_module(root)) return fs::absolute(root, ec).string();
    return "";
}

HtmlReportOutcome write_html_report(const std::string& folder)
{
    HtmlReportOutcome outcome;
    const std::string how = "python3 -m plots.html_report " + folder + " (from the repository root)";
    std::error_code ec;
    if (!fs::is_regular_file(PYTHON, ec)) {
        outcome.message = std::string(PYTHON) + " not found: install Debian's python3 and its packages (`make deps`)";
        return outcome;
    }
    const std::string root = plots_root();
    if (root.empty()) {
        outcome.message = "plots/html_report.py not found (set CB_PLOTS_ROOT to the repository); then run " + how;
        return outcome;
    }
    // The child finds `plots` through PYTHONPATH; this process ends soon after, so its environment
    // is changed in place rather than building a new one for execve.
    const char* old = std::getenv("PYTHONPATH");
    const std::string path = root + (old && *old ? ":" + std::string(old) : "");
    ::setenv("PYTHONPATH", path.c_str(), 1);
    ::setenv("MPLBACKEND", "Agg", 0);
    TempFolder temp("cb-report");
    const fs::path out = temp.path() / "stdout", err = temp.path() / "stderr";
    const ProgramOutcome run = run_program({PYTHON, "-m", "plots.html_report", fs::absolute(folder, ec).string()},
                                           out.string(), err.string(), ProgramOptions{600.0});
    const std::string said = trimmed(read_all(err));
    if (run.failure().empty()) {
        outcome.written = true;
        outcome.exit_status = 0;
        outcome.path = (fs::absolute(folder, ec) / "report" / "index.html").lexically_normal().string();
        return outcome;
    }
    outcome.exit_status = run.exit_status == 2 ? 2 : 1;
    const std::string prefix = "html_report: error: ";
    if (run.exit_status == 2 && said.rfind(prefix, 0) == 0)
        outcome.message = said.substr(prefix.size());  // the folder is refused: the script's own words
    else if (said.find("ModuleNotFoundError") != std::string::npos)
        outcome.message = "a Python package is missing (`make deps` installs them): " +
                          said.substr(said.rfind('\n') == std::string::npos ? 0 : said.rfind('\n') + 1);
    else
        outcome.message = "plots/html_report.py " + run.failure() + (said.empty() ? "" : ": " + said);
    return outcome;
}

void report_at_end(const std::string& folder, std::ostream& out)
{
    if (const char* env = std::getenv("CB_REPORT"); env && std::string(env) == "0") {
        out << "report: not written (CB_REPORT=0); write it with `contactbench report " << folder << "`\n";
        return;
    }
    try {
        const HtmlReportOutcome r = write_html_report(folder);
        if (r.written)
            out << "report: " << r.path << " (open it in a browser; it needs no network)\n";
        else
            out << "report: not written: " << r.message << "\n        then: contactbench report " << folder << "\n";
    } catch (const std::exception& e) {
        out << "report: not written: " << e.what() << "\n        then: contactbench report " << folder << "\n";
    }
}

}  // namespace cb
