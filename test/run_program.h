// test/run_program.h - tests that run a program of the project as a child process: the mbr tool
// (test_mbr_tool.cpp) and the tutorial's chapter programs (test_tutorial_*.cpp). The program is
// started with posix_spawn, no shell, so that paths may hold spaces; its stdout and stderr are
// captured, and a run that has not ended after five minutes is killed, so that a hang fails the
// test instead of stopping the suite (a guard, not a measurement).
//
// MBR_EXAMPLES_DIR (test/CMakeLists.txt) names the folder of the built example programs.
#pragma once

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <ostream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace mbr::test {

/// What a run of a program did: its exit status (-signal when a signal ended it), stdout, stderr.
struct ProgramRun {
    int status = -1;
    std::string out, err;
};

inline std::ostream& operator<<(std::ostream& os, const ProgramRun& r) {
    return os << "status " << r.status << "\nstdout:\n" << r.out << "stderr:\n" << r.err;
}

/// A fresh folder under the system's temporary folder, with a space in its name, removed at the
/// end with everything in it.
class TempFolder {
public:
    TempFolder() {
        std::string pattern = (std::filesystem::temp_directory_path() / "mbr test XXXXXX").string();
        REQUIRE(::mkdtemp(pattern.data()) != nullptr);
        path_ = pattern;
    }
    ~TempFolder() {
        std::error_code ec;
        std::filesystem::remove_all(path_, ec);
    }
    TempFolder(const TempFolder&) = delete;
    TempFolder& operator=(const TempFolder&) = delete;

    std::string operator/(const std::string& name) const { return (path_ / name).string(); }
    const std::filesystem::path& path() const { return path_; }
    /// Writes `text` to the file `name` in the folder (bytes as given) and returns its path.
    std::string write(const std::string& name, const std::string& text) const {
        const std::string p = (path_ / name).string();
        std::ofstream(p, std::ios::binary) << text;
        return p;
    }

private:
    std::filesystem::path path_;
};

/// An anonymous file for one captured stream (unlinked at once; the descriptor keeps it).
inline int capture_file() {
    std::string name = (std::filesystem::temp_directory_path() / "mbr capture XXXXXX").string();
    const int fd = ::mkstemp(name.data());
    REQUIRE(fd >= 0);
    ::unlink(name.c_str());
    return fd;
}

/// Everything written to the descriptor, from its start.
inline std::string read_fd(int fd) {
    std::string s;
    ::lseek(fd, 0, SEEK_SET);
    char buffer[4096];
    for (ssize_t n; (n = ::read(fd, buffer, sizeof buffer)) > 0;) s.append(buffer, size_t(n));
    return s;
}

/// A program started by start_program and not yet waited for.
struct StartedProgram {
    pid_t pid = -1;
    int out_fd = -1, err_fd = -1;
    bool own_err = true;  // err_fd is a capture file of ours (not the caller's stderr_fd)
    std::string program;
};

/// Starts `program ARGS...` with stdin from /dev/null and stdout and stderr captured, or stderr
/// on `stderr_fd` when that is given (its content is then the caller's to read). The environment
/// is inherited. finish_program() waits for it.
inline StartedProgram start_program(const std::string& program,
                                    const std::vector<std::string>& args, int stderr_fd = -1) {
    StartedProgram started;
    started.program = program;
    started.out_fd = capture_file();
    started.own_err = stderr_fd < 0;
    started.err_fd = stderr_fd >= 0 ? stderr_fd : capture_file();
    std::vector<std::string> words = {program};
    words.insert(words.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (std::string& w : words) argv.push_back(w.data());
    argv.push_back(nullptr);

    posix_spawn_file_actions_t actions;
    REQUIRE(posix_spawn_file_actions_init(&actions) == 0);
    posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_adddup2(&actions, started.out_fd, 1);
    posix_spawn_file_actions_adddup2(&actions, started.err_fd, 2);
    posix_spawn_file_actions_addclose(&actions, started.out_fd);
    if (started.err_fd != 2) posix_spawn_file_actions_addclose(&actions, started.err_fd);
    const int spawned =
        posix_spawn(&started.pid, program.c_str(), &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    INFO("posix_spawn of " << program);
    REQUIRE(spawned == 0);
    return started;
}

/// Waits for a started program (killing it after five minutes) and returns what it did.
inline ProgramRun finish_program(StartedProgram& started) {
    int wait_status = 0;
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::minutes(5);
    pid_t done = 0;
    while ((done = ::waitpid(started.pid, &wait_status, WNOHANG)) == 0 &&
           std::chrono::steady_clock::now() < give_up)
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    if (done == 0) {
        ::kill(started.pid, SIGKILL);
        ::waitpid(started.pid, &wait_status, 0);
    }
    ProgramRun run;
    run.out = read_fd(started.out_fd);
    ::close(started.out_fd);
    if (started.own_err) {
        run.err = read_fd(started.err_fd);
        ::close(started.err_fd);
    }
    INFO(started.program << " did not end within five minutes");
    REQUIRE(done == started.pid);
    run.status = WIFEXITED(wait_status) ? WEXITSTATUS(wait_status) : -WTERMSIG(wait_status);
    return run;
}

/// Runs `program ARGS...` as start_program starts it and waits for it.
inline ProgramRun run_program(const std::string& program, const std::vector<std::string>& args,
                              int stderr_fd = -1) {
    StartedProgram started = start_program(program, args, stderr_fd);
    return finish_program(started);
}

#ifdef MBR_EXAMPLES_DIR
/// Runs the example program `name` (built into MBR_EXAMPLES_DIR) with ARGS.
inline ProgramRun run_example(const std::string& name, const std::vector<std::string>& args) {
    return run_program(std::string(MBR_EXAMPLES_DIR) + "/" + name, args);
}
#endif

/// The number printed right after the first occurrence of `label` in `text` (spaces, '=' and
/// ':' between them are skipped), so that a test can read a program's report as a student reads
/// it. Fails the test when the label is missing or no number follows it.
inline double number_after(const std::string& text, const std::string& label) {
    const size_t at = text.find(label);
    INFO("looking for \"" << label << "\" in:\n" << text);
    REQUIRE(at != std::string::npos);
    size_t i = at + label.size();
    while (i < text.size() && (text[i] == ' ' || text[i] == '=' || text[i] == ':')) ++i;
    const char* begin = text.c_str() + i;
    char* end = nullptr;
    const double value = std::strtod(begin, &end);
    REQUIRE(end != begin);
    return value;
}

/// The whitespace-separated fields of the first line of `text` whose first field is `first`
/// (a row of a program's table); fails the test when there is none.
inline std::vector<std::string> row_fields(const std::string& text, const std::string& first) {
    std::istringstream lines(text);
    for (std::string line; std::getline(lines, line);) {
        std::istringstream words(line);
        std::vector<std::string> fields;
        for (std::string w; words >> w;) fields.push_back(w);
        if (!fields.empty() && fields[0] == first) return fields;
    }
    FAIL("no line starts with \"" << first << "\" in:\n" << text);
    return {};
}

}  // namespace mbr::test
