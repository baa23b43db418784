// examples/common/progress.h - progress of a long run on stderr, in every stage: reading the
// scene, building the octree, the hidden regions, the work inside each shot, rendering
// (docs/scene-format.md, "Progress"). On a terminal one line is redrawn in place (with a bar and
// an estimate of the time left where the stage knows its fraction); elsewhere (a pipe, a log
// file) a line every few seconds, the first within five seconds of the start, so that a run that
// is killed has said what it was doing and short runs stay silent.
#pragma once

#include <condition_variable>
#include <mutex>
#include <string>
#include <thread>

namespace mbr {

/// A duration for a progress line: "42 s" below 100 s, "38 min" below two hours, else "3.5 h".
std::string format_duration(double seconds);

/// Reports the current stage of a run from a thread of its own, so that a stage with no
/// intermediate events (building an octree, a long first shot) still shows it is alive. The
/// run's thread sets what is being done (stage, update); every call is cheap and thread-safe.
class ProgressReporter {
public:
    /// `on`: report at all (false for --quiet). Writes to stderr, as a terminal when it is one;
    /// off a terminal a line every `interval` seconds.
    explicit ProgressReporter(bool on, double interval = default_interval);
    /// Stops the reporting thread and clears the line on a terminal.
    ~ProgressReporter();
    ProgressReporter(const ProgressReporter&) = delete;
    ProgressReporter& operator=(const ProgressReporter&) = delete;

    /// A new stage, described by `text` ("building the octree: 4,096 polygons"); its clock
    /// starts now. An empty text: idle (nothing is shown).
    void stage(const std::string& text);
    /// Within the stage: what is done so far (`text`, shown after the stage's) and, when known,
    /// the fraction of the stage done (0..1) for the bar and the estimate of the time left;
    /// a negative fraction when unknown. A fraction of 1 that ends a stage shown off a terminal
    /// is printed at once, so that the log says the stage ended.
    void update(const std::string& text, double fraction = -1);
    /// Like update, with the estimate of the time left given by the caller (seconds, < 0:
    /// none), for stages whose fraction is not linear in time (the shots). Between events the
    /// line counts the estimate down, and drops it once it has run out (a shot whose first
    /// transfers are slow is not "about 1 s left" for minutes).
    void update(const std::string& text, double fraction, double seconds_left);

    /// Seconds between lines off a terminal, by default.
    static constexpr double default_interval = 5;

private:
    void run();                                 // the reporting thread
    std::string line_locked(double now) const;  // the line to show; mutex_ held
    void show_locked(const std::string& line);
    void draw_now_locked();  // on a terminal, an event's redraw (throttled)

    bool on_ = false;
    bool terminal_ = false;
    double interval_ = default_interval;
    std::mutex mutex_;
    std::condition_variable wake_;
    bool stop_ = false;
    std::string stage_, detail_;
    double fraction_ = -1, seconds_left_ = -1;
    double estimated_at_ = 0;  // when seconds_left_ was given: the line counts down from it
    double stage_start_ = 0, start_ = 0;
    double next_line_ = 0;     // off a terminal: when the next line is due (run time)
    bool drawn_ = false;       // a line is on the terminal, to be cleared at the end
    double last_draw_ = -1e9;  // when the terminal's line was last drawn
    std::thread thread_;
};

}  // namespace mbr
